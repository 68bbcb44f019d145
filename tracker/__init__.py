"""TMEye tracker core: a pure library (numpy, OpenCV, SciPy, FilterPy).

No asyncio, web framework, database or WebRTC imports here: a researcher can use it without the server.
"""

__all__ = ["__version__"]
__version__ = "0.1.0"
