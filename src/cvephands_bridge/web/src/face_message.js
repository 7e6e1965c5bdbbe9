// Face video messages ("CVVF", include/cvephands_bridge/video/face_video.h): a participant's
// face as a small JPEG (thesis 7.5), relayed like the hands. Validates the layout and the
// checksum; the JPEG itself is left to the browser's decoder.
import { crc32 } from './hand_decoder.js';

const HEADER = 24;
const MAX_JPEG = 512 * 1024;
const MAX_SIDE = 1024;

export function isFaceMessage(bytes) {
  return bytes.length >= 4 && bytes[0] === 0x43 && bytes[1] === 0x56 && bytes[2] === 0x56 &&
    bytes[3] === 0x46;
}

// bytes: Uint8Array -> { ok: true, stampMs, width, height, jpeg: Uint8Array } | { ok: false, reason }
export function parseFaceMessage(bytes) {
  const fail = (reason) => ({ ok: false, reason });
  if (!(bytes instanceof Uint8Array) || !isFaceMessage(bytes)) return fail('not a face message (magic)');
  if (bytes.length < HEADER + 4) return fail('truncated header');
  const v = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  if (bytes[4] !== 1) return fail(`unsupported version ${bytes[4]}`);
  if (bytes[5] !== 1) return fail(`unsupported format ${bytes[5]}`);
  if (v.getUint16(6, true) !== 0) return fail('reserved field not 0');
  const sec = v.getUint32(8, true);
  const nsec = v.getUint32(12, true);
  if (nsec >= 1e9) return fail('nanoseconds >= 10^9');
  const width = v.getUint16(16, true);
  const height = v.getUint16(18, true);
  if (width < 1 || height < 1 || width > MAX_SIDE || height > MAX_SIDE) return fail('picture size out of range');
  const n = v.getUint32(20, true);
  if (n < 1 || n > MAX_JPEG) return fail('JPEG size out of range');
  if (bytes.length !== HEADER + n + 4) return fail('size does not match the JPEG size');
  if (v.getUint32(HEADER + n, true) !== crc32(bytes.subarray(0, HEADER + n))) return fail('checksum mismatch');
  return { ok: true, stampMs: sec * 1000 + nsec / 1e6, width, height, jpeg: bytes.subarray(HEADER, HEADER + n) };
}
