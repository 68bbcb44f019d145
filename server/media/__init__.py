"""Live video to browsers: WebRTC tracks that send the media pipeline's H.264 packets as they are."""
