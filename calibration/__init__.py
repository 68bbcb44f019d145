"""TMEye stereo calibration (issue 3): a pure library (numpy, OpenCV, SciPy).

Stage 1 (paper §4): lens distortion, either the paper's polynomial model eq. (3)-(4) or pinhole with
Brown-Conrady distortion. Stage 2 (paper §5): camera rotation R (Euler angles, eq. 6) and translation T
by bundle adjustment (eq. 5, 7-8). No asyncio, web framework or database imports here.
"""

from calibration.errors import (
    BoardSizeError,
    CalibrationError,
    ImageMismatchError,
    TooFewViewsError,
    UnreadableImageError,
)

__all__ = [
    "BoardSizeError",
    "CalibrationError",
    "ImageMismatchError",
    "TooFewViewsError",
    "UnreadableImageError",
]
