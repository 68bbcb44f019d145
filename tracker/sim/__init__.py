"""The simulated stereo rig: rendered cameras on a simulated gimbal, with ground truth (the default source)."""
