"""Media: one H.264 encoder per camera fed by the runtime (`MediaPipeline`), whose packets serve every
WebRTC viewer and the recorder, and a shared JPEG stream for the MJPEG fallback. No per-viewer encoding."""
