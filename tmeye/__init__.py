"""The `tmeye` command: thin front ends over the tracker and calibration libraries."""
