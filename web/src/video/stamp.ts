// Painting a video's presented frame into a canvas, and reading the frame index the server's measurement
// mode (--stamp-frames) draws into each picture.

const STAMP_BITS = 16, STAMP_CELL = 8;
let stampCanvas: HTMLCanvasElement | null = null;

/** Paint the frame a video presents now into a canvas of the video's own size (CSS scales it like the video). */
export function paint(picture: HTMLCanvasElement, video: HTMLVideoElement): void {
  const w = video.videoWidth, h = video.videoHeight;
  if (!w || !h) return;
  if (picture.width !== w || picture.height !== h) {
    picture.width = w;
    picture.height = h;
  }
  picture.getContext("2d", { alpha: false })?.drawImage(video, 0, 0, w, h);
}

/** The frame index the server's measurement mode (--stamp-frames) draws in the top-left corner: 16 cells of
 * 8x8 px, most significant bit first, white for 1. srcW: the source's width (the picture may be scaled). */
export function readStamp(video: HTMLVideoElement | HTMLCanvasElement, srcW: number): number | null {
  const width = video instanceof HTMLVideoElement ? video.videoWidth : video.width;
  const scale = width > 0 ? width / srcW : 1;
  const w = STAMP_BITS * STAMP_CELL;
  stampCanvas ??= document.createElement("canvas");
  stampCanvas.width = w;
  stampCanvas.height = STAMP_CELL;
  const c = stampCanvas.getContext("2d", { willReadFrequently: true });
  if (!c) return null;
  c.drawImage(video, 0, 0, w * scale, STAMP_CELL * scale, 0, 0, w, STAMP_CELL);
  const px = c.getImageData(0, 0, w, STAMP_CELL).data;
  let v = 0;
  for (let k = 0; k < STAMP_BITS; k++) {
    const i = ((STAMP_CELL / 2) * w + k * STAMP_CELL + STAMP_CELL / 2) * 4;
    const grey = (px[i] + px[i + 1] + px[i + 2]) / 3;
    v = (v << 1) | (grey > 127 ? 1 : 0);
  }
  return v;
}
