// WebRTC reception of both cameras: two receive-only video transceivers (the first gets the left camera,
// the second the right), H.264 preferred, non-trickle ICE (gathering completes before the offer is sent),
// ICE servers from GET /api/webrtc/config.
import { api, ApiError } from "../api/client";

export class VideoUnavailable extends Error {}

export interface RtcVideo {
  pc: RTCPeerConnection;
  left: MediaStream;
  right: MediaStream;
  close(): void;
}

function iceServers(list: (string | RTCIceServer)[]): RTCIceServer[] {
  return list.map((s) => (typeof s === "string" ? { urls: s } : s));
}

function waitGathering(pc: RTCPeerConnection, timeoutMs: number): Promise<void> {
  if (pc.iceGatheringState === "complete") return Promise.resolve();
  return new Promise((resolve) => {
    const done = () => {
      pc.removeEventListener("icegatheringstatechange", check);
      clearTimeout(timer);
      resolve();
    };
    const check = () => {
      if (pc.iceGatheringState === "complete") done();
    };
    const timer = setTimeout(done, timeoutMs);
    pc.addEventListener("icegatheringstatechange", check);
  });
}

function preferH264(t: RTCRtpTransceiver): void {
  const caps = typeof RTCRtpReceiver !== "undefined" && RTCRtpReceiver.getCapabilities?.("video");
  if (!caps || !t.setCodecPreferences) return;
  const h264 = caps.codecs.filter((c) => c.mimeType.toLowerCase() === "video/h264");
  const rest = caps.codecs.filter((c) => c.mimeType.toLowerCase() !== "video/h264");
  if (h264.length) {
    try {
      t.setCodecPreferences([...h264, ...rest]);
    } catch {
      /* keep the browser's order */
    }
  }
}

export async function startWebRtc(onState: (s: RTCPeerConnectionState) => void): Promise<RtcVideo> {
  if (typeof RTCPeerConnection === "undefined") throw new VideoUnavailable("this browser has no WebRTC");
  let servers: RTCIceServer[] = [];
  try {
    const cfg = await api.webrtcConfig();
    servers = iceServers(cfg.ice_servers ?? []);
  } catch (e) {
    if (e instanceof ApiError && e.status === 404) throw new VideoUnavailable("the server offers no WebRTC video");
    if (e instanceof ApiError && (e.status === 401 || e.offline)) throw e;
    // another answer: try without ICE servers
  }
  const pc = new RTCPeerConnection({ iceServers: servers });
  const close = () => {
    try {
      pc.close();
    } catch {
      /* closed */
    }
  };
  try {
    const tl = pc.addTransceiver("video", { direction: "recvonly" });
    const tr = pc.addTransceiver("video", { direction: "recvonly" });
    preferH264(tl);
    preferH264(tr);
    pc.addEventListener("connectionstatechange", () => onState(pc.connectionState));
    await pc.setLocalDescription(await pc.createOffer());
    await waitGathering(pc, 3000);
    const local = pc.localDescription!;
    let answer;
    try {
      answer = await api.webrtcOffer({ sdp: local.sdp, type: "offer" });
    } catch (e) {
      if (e instanceof ApiError && e.status === 404) throw new VideoUnavailable("the server offers no WebRTC video");
      throw e;
    }
    await pc.setRemoteDescription({ type: "answer", sdp: answer.sdp });
    const left = new MediaStream([tl.receiver.track]);
    const right = new MediaStream([tr.receiver.track]);
    await new Promise<void>((resolve, reject) => {
      const timer = setTimeout(() => reject(new Error("WebRTC did not connect within 10 s")), 10000);
      const check = () => {
        if (pc.connectionState === "connected") {
          clearTimeout(timer);
          resolve();
        } else if (pc.connectionState === "failed" || pc.connectionState === "closed") {
          clearTimeout(timer);
          reject(new Error(`WebRTC connection ${pc.connectionState}`));
        }
      };
      pc.addEventListener("connectionstatechange", check);
      check();
    });
    return { pc, left, right, close };
  } catch (e) {
    close();
    throw e;
  }
}

/** Whether the server answers the MJPEG stream (reads the headers, then lets go). */
export async function mjpegAvailable(camera: "left" | "right"): Promise<boolean> {
  const ctrl = new AbortController();
  const timer = setTimeout(() => ctrl.abort(), 5000);
  try {
    const res = await fetch(`/api/live/${camera}.mjpeg`, { signal: ctrl.signal, credentials: "same-origin" });
    ctrl.abort();
    return res.ok;
  } catch {
    return false;
  } finally {
    clearTimeout(timer);
  }
}
