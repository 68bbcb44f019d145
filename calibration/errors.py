"""Calibration input errors: each a ValueError subclass carrying a one-line message for the CLI."""

from __future__ import annotations


class CalibrationError(ValueError):
    """An input problem that stops a calibration (printed as one line by `tmeye calibrate`)."""


class TooFewViewsError(CalibrationError):
    """Fewer usable board views than the minimum the solver needs."""


class ImageMismatchError(CalibrationError):
    """Left and right image sets differ in count or image size."""


class UnreadableImageError(CalibrationError):
    """An image file could not be read or decoded."""


class BoardSizeError(CalibrationError):
    """No image shows a board with the given inner-corner count (the --board argument is wrong)."""
