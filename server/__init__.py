"""The TMEye operator console server: `create_app(settings)` (server.app) composes the runtime, the
database and the routers; `tmeye serve` runs it under uvicorn."""
