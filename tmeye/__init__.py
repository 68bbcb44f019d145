"""The `tmeye` command: thin front ends over the tracker and calibration libraries."""

import os

# The tracker does its per-pixel work in OpenCV on one thread; numpy's OpenBLAS would otherwise start a
# pool of threads for the small matrix products of each frame and keep them spinning on the other cores
# (measured: most of the per-frame instructions). Set before numpy is first imported; a user's own
# setting wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

__version__ = "0.2.0"
