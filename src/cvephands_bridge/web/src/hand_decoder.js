// Decoder of the hand stream codec: a port of HandStreamDecoder
// (src/stream/hand_stream_decoder.cpp; wire format in
// include/cvephands_bridge/stream/hand_stream_codec.h). It gives byte-identical volumes and
// rejects what the C++ decoder rejects, with the same reasons, up to two kinds of zstd frame
// that libzstd never writes (the CRC-32 over the message comes first, so only a broken encoder
// can send them): fzstd does not check everything libzstd does inside compressed blocks (e.g.
// match offsets before the start of the output), so a corrupt block may decode here to other
// bytes; and a window descriptor larger than the content is refused here (fzstd would allocate
// it). fzstd also skips the frame checks libzstd makes before decoding; they are done here.
import { Decompress } from 'fzstd';

const HEADER_SIZE = 92;
const TRAILER_SIZE = 4; // CRC-32
const VERSION = 1;
const MAX_SIDE = 256;
const MAX_VOXEL_SIZE = 1.0; // m
const MAX_ABS_ORIGIN = 1.0e4; // m
const MAX_SHIFT = 256; // voxels, per axis
const CONTEXTS = 12; // side (2) x opposite-side neighbours (1..6)
const MAX_BITS = 8;
const FLAG_DELTA = 1;
const METHOD_RAW = 0;
const METHOD_BAND = 1;
const MAX_REFERENCES = 16;

// ---- CRC-32 (zlib / PNG polynomial) and varints, as in src/stream/hand_stream_format.h --------

const CRC_TABLE = (() => {
  const t = new Uint32Array(256);
  for (let n = 0; n < 256; ++n) {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    t[n] = c >>> 0;
  }
  return t;
})();

// CRC-32 of bytes[0, end): crc32("123456789") = 0xcbf43926.
export function crc32(bytes, end = bytes.length) {
  let c = 0xffffffff;
  for (let i = 0; i < end; ++i) c = CRC_TABLE[(c ^ bytes[i]) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

// One unsigned LEB128 varint from bytes[pos, end): [value, next position], or null when it is
// unterminated or longer than 4 bytes (the format's values are below 2^24).
export function readVarint(bytes, pos, end) {
  let v = 0;
  for (let i = 0; i < 4 && pos < end; ++i) {
    const b = bytes[pos++];
    v |= (b & 0x7f) << (7 * i);
    if (!(b & 0x80)) return [v, pos];
  }
  return null;
}

const levelsFor = (bits) => 1 << bits;
const tableBytes = (bits) => CONTEXTS << bits;
const codesPerByte = (bits) => (bits === 0 ? 0 : Math.floor(8 / bits));
function codeBytes(bandCount, bits) {
  const k = codesPerByte(bits);
  return k === 0 ? 0 : Math.ceil(bandCount / k);
}

// ---- zstd frame checks libzstd makes and fzstd does not ---------------------------------------

const ZSTD_MAGIC = 0xfd2fb528;
const ZSTD_SKIPPABLE_START = 0x184d2a50; // magic & 0xfffffff0 of a skippable frame
const ZSTD_BLOCK_SIZE_MAX = 1 << 17;
const CONTENT_UNKNOWN = -1;
const u32 = (b, p) => (b[p] | (b[p + 1] << 8) | (b[p + 2] << 16) | (b[p + 3] << 24)) >>> 0;

// The frame header as ZSTD_getFrameHeader reads it (libzstd 1.5), or null where
// ZSTD_getFrameContentSize says ZSTD_CONTENTSIZE_ERROR. contentSize: CONTENT_UNKNOWN, or a
// number with its decimal text (a u64 may exceed 2^53).
function zstdFrameHeader(p) {
  if (p.length < 5) return null;
  const magic = u32(p, 0);
  if (magic !== ZSTD_MAGIC) {
    if ((magic & 0xfffffff0) >>> 0 !== ZSTD_SKIPPABLE_START || p.length < 8) return null;
    return { contentSize: 0, contentText: '0' }; // what ZSTD_getFrameContentSize says
  }
  const fhd = p[4];
  const single = (fhd >> 5) & 1;
  const dictBytes = [0, 1, 2, 4][fhd & 3];
  const fcsId = fhd >> 6;
  const headerSize = 5 + (1 - single) + dictBytes + [0, 2, 4, 8][fcsId] + (single && !fcsId ? 1 : 0);
  if (p.length < headerSize || fhd & 0x08) return null; // incomplete, or the reserved bit
  let pos = 5;
  let windowSize = 0;
  if (!single) {
    const windowLog = (p[pos] >> 3) + 10;
    if (windowLog > 31) return null;
    windowSize = 2 ** windowLog * (1 + (p[pos] & 7) / 8);
    ++pos;
  }
  let dictId = 0;
  for (let i = 0; i < dictBytes; ++i) dictId += p[pos + i] * 2 ** (8 * i);
  pos += dictBytes;
  let contentSize = CONTENT_UNKNOWN;
  let contentText = '';
  if (fcsId === 0 && single) contentSize = p[pos];
  else if (fcsId === 1) contentSize = (p[pos] | (p[pos + 1] << 8)) + 256;
  else if (fcsId === 2) contentSize = u32(p, pos);
  else if (fcsId === 3) {
    const lo = u32(p, pos);
    const hi = u32(p, pos + 4);
    // 2^64 - 1 and 2^64 - 2 are libzstd's UNKNOWN and ERROR sentinels.
    if (hi === 0xffffffff && lo >= 0xfffffffe) {
      if (lo === 0xfffffffe) return null;
    } else {
      contentSize = hi * 2 ** 32 + lo;
      contentText = ((BigInt(hi) << 32n) | BigInt(lo)).toString();
    }
  }
  if (contentSize !== CONTENT_UNKNOWN && !contentText) contentText = String(contentSize);
  if (single) windowSize = contentSize;
  return { headerSize, windowSize, dictId, contentSize, contentText, checksum: (fhd >> 2) & 1 };
}

// ZSTD_findFrameCompressedSize for a non-skippable frame with a valid header: { size,
// largestCompressedBlock }, or { error } with libzstd's error text.
function zstdFrameSize(p, header) {
  let pos = header.headerSize;
  let largestCompressedBlock = 0;
  for (;;) {
    if (p.length - pos < 3) return { error: 'Src size is incorrect' };
    const h = p[pos] | (p[pos + 1] << 8) | (p[pos + 2] << 16);
    const type = (h >> 1) & 3;
    if (type === 3) return { error: 'Data corruption detected' }; // reserved block type
    const size = type === 1 ? 1 : h >>> 3; // an RLE block stores one byte
    if (type === 2) largestCompressedBlock = Math.max(largestCompressedBlock, size);
    if (3 + size > p.length - pos) return { error: 'Src size is incorrect' };
    pos += 3 + size;
    if (h & 1) break; // last block
  }
  if (header.checksum) {
    if (p.length - pos < 4) return { error: 'Src size is incorrect' };
    pos += 4;
  }
  return { size: pos, largestCompressedBlock };
}

// Decompresses one checked frame into out (exactly its content size): null, or libzstd's error
// text. The streaming decoder reports every block, so the output size is checked exactly; its
// window is the content size (single-segment frames) or the window descriptor's size, which
// zstdDecompress bounds first.
function zstdDecompress(p, header, frame, out) {
  if (header.dictId) return 'Dictionary mismatch';
  if (frame.largestCompressedBlock > ZSTD_BLOCK_SIZE_MAX) return 'Src size is incorrect';
  // libzstd writes a window descriptor only for windows smaller than the content; a larger one
  // would make fzstd allocate it (up to 2 GB). libzstd would decode such a frame.
  if (header.windowSize > out.length) return 'window larger than the content (not supported)';
  let size = 0;
  let overflow = false;
  try {
    const d = new Decompress((block) => {
      if (size + block.length > out.length) overflow = true;
      else out.set(block, size);
      size += block.length;
    });
    d.push(p, true);
  } catch {
    // fzstd throws on what it finds corrupt, and on a block larger than its window (after it
    // was reported: an overflow).
    if (!overflow) return 'Data corruption detected';
  }
  if (overflow) return 'Destination buffer is too small';
  if (size !== out.length) return 'Data corruption detected';
  if (header.checksum && xxh64Low32(out) !== u32(p, p.length - 4))
    return "Restored data doesn't match checksum";
  return null;
}

// ---- XXH64 (zstd's frame checksum is its low 32 bits), in 32-bit halves -------------------------

// Unsigned 64-bit values as [high, low] 32-bit halves.
const P1 = [0x9e3779b1, 0x85ebca87];
const P2 = [0xc2b2ae3d, 0x27d4eb4f];
const P3 = [0x165667b1, 0x9e3779f9];
const P4 = [0x85ebca77, 0xc2b2ae63];
const P5 = [0x27d4eb2f, 0x165667c5];

function add64(a, b) {
  const lo = a[1] + b[1];
  return [(a[0] + b[0] + (lo > 0xffffffff ? 1 : 0)) >>> 0, lo >>> 0];
}
// High half of the 64-bit product of two u32 (16-bit split keeps every step exact).
function mulHigh32(a, b) {
  return Math.floor(((a >>> 16) * b + Math.floor((a & 0xffff) * b / 65536)) / 65536);
}
function mul64(a, b) {
  const hi = mulHigh32(a[1], b[1]) + Math.imul(a[0], b[1]) + Math.imul(a[1], b[0]);
  return [hi >>> 0, Math.imul(a[1], b[1]) >>> 0];
}
const xor64 = (a, b) => [(a[0] ^ b[0]) >>> 0, (a[1] ^ b[1]) >>> 0];
const rotl64 = (a, r) => [
  ((a[0] << r) | (a[1] >>> (32 - r))) >>> 0, // 0 < r < 32 here
  ((a[1] << r) | (a[0] >>> (32 - r))) >>> 0,
];
// a >> s for 0 < s <= 33 as used by the avalanche.
const shr64 = (a, s) =>
  s >= 32 ? [0, a[0] >>> (s - 32)] : [a[0] >>> s, ((a[1] >>> s) | (a[0] << (32 - s))) >>> 0];
const read64 = (b, p) => [u32(b, p + 4), u32(b, p)];
const round64 = (acc, input) => mul64(rotl64(add64(acc, mul64(input, P2)), 31), P1);
const merge64 = (acc, v) => add64(mul64(xor64(acc, round64([0, 0], v)), P1), P4);

// Low 32 bits of XXH64(data, seed 0).
export function xxh64Low32(data) {
  const n = data.length;
  let p = 0;
  let h;
  if (n >= 32) {
    let v1 = add64(P1, P2);
    let v2 = P2;
    let v3 = [0, 0];
    let v4 = [(0 - P1[0] - (P1[1] ? 1 : 0)) >>> 0, (0 - P1[1]) >>> 0]; // -P1 mod 2^64
    for (; p + 32 <= n; p += 32) {
      v1 = round64(v1, read64(data, p));
      v2 = round64(v2, read64(data, p + 8));
      v3 = round64(v3, read64(data, p + 16));
      v4 = round64(v4, read64(data, p + 24));
    }
    h = add64(add64(rotl64(v1, 1), rotl64(v2, 7)), add64(rotl64(v3, 12), rotl64(v4, 18)));
    h = merge64(merge64(merge64(merge64(h, v1), v2), v3), v4);
  } else {
    h = P5;
  }
  h = add64(h, [Math.floor(n / 2 ** 32), n >>> 0]);
  for (; p + 8 <= n; p += 8)
    h = add64(mul64(rotl64(xor64(h, round64([0, 0], read64(data, p))), 27), P1), P4);
  if (p + 4 <= n) {
    h = add64(mul64(rotl64(xor64(h, mul64([0, u32(data, p)], P1)), 23), P2), P3);
    p += 4;
  }
  for (; p < n; ++p) h = mul64(rotl64(xor64(h, mul64([0, data[p]], P5)), 11), P1);
  h = mul64(xor64(h, shr64(h, 33)), P2);
  h = mul64(xor64(h, shr64(h, 29)), P3);
  return xor64(h, shr64(h, 32))[1];
}

// ---- mask prediction ----------------------------------------------------------------------------

// out(x,y,z) = mask(x + sx, y + sy, z + sz), 0 outside the mask's volume: a delta frame's
// prediction.
function shiftedMask(mask, nx, ny, nz, sx, sy, sz, out) {
  const x0 = Math.max(0, -sx);
  const x1 = Math.min(nx, nx - sx);
  for (let z = 0; z < nz; ++z)
    for (let y = 0; y < ny; ++y) {
      const row = nx * (y + ny * z);
      const ry = y + sy;
      const rz = z + sz;
      if (ry < 0 || ry >= ny || rz < 0 || rz >= nz || x0 >= x1) {
        out.fill(0, row, row + nx);
        continue;
      }
      out.fill(0, row, row + x0);
      const src = nx * (ry + ny * rz) + x0 + sx;
      out.set(mask.subarray(src, src + x1 - x0), row + x0);
      out.fill(0, row + x1, row + nx);
    }
}

// ---- the decoder ------------------------------------------------------------------------------

export class HandStreamDecoder {
  // The last decoded frame per target (what its next delta frame is predicted from):
  // { target, sequence, dims, voxelSize, isoByte, lastUse, above }.
  #refs = [];
  #tick = 0;
  // Scratch kept between messages (a hand stream repeats its dims): above (0 / 255 bytes,
  // swapped with the references' masks), padded, occupied; the band's raster indices and
  // contexts.
  #buf = {};
  #bandIndex = new Int32Array(0);
  #bandContext = new Uint8Array(0);

  // Forgets all reference frames (delta frames are rejected until the next key frame).
  reset() {
    this.#refs = [];
  }

  // Never throws on bad input. On success: { ok: true, frame, info }; otherwise
  // { ok: false, reason } with the reference frames kept as they were. Allocation: up to ~18
  // bytes per sample of the message's dims (300 MB at 256^3; the C++ decoder needs ~10, fzstd
  // keeps a window as large as the payload), only once the header, the checksum and the zstd
  // frame header agree on the sizes.
  decode(bytes) {
    const fail = (reason) => ({ ok: false, reason });
    if (bytes instanceof ArrayBuffer) bytes = new Uint8Array(bytes);
    if (!(bytes instanceof Uint8Array)) return fail('not a Uint8Array');
    const size = bytes.length;

    // ---- envelope: size, magic, version, length, checksum ----
    if (size < HEADER_SIZE + TRAILER_SIZE)
      return fail(
        `truncated header: ${size} bytes, a message has at least ${HEADER_SIZE + TRAILER_SIZE}`,
      );
    if (bytes[0] !== 0x43 || bytes[1] !== 0x56 || bytes[2] !== 0x48 || bytes[3] !== 0x53)
      return fail('bad magic (not a hand stream message)');
    if (bytes[4] !== VERSION)
      return fail(`unsupported version ${bytes[4]} (this decoder reads ${VERSION})`);
    const h = readHeader(bytes);
    if (HEADER_SIZE + h.payloadSize + TRAILER_SIZE !== size)
      return fail(
        `size mismatch: header says ${h.payloadSize} payload bytes, message has ` +
          `${size - HEADER_SIZE - TRAILER_SIZE}`,
      );
    if (crc32(bytes, size - TRAILER_SIZE) !== u32(bytes, size - TRAILER_SIZE))
      return fail('checksum mismatch');

    // ---- header fields ----
    if (h.method !== METHOD_RAW && h.method !== METHOD_BAND)
      return fail(`unknown method ${h.method}`);
    if (h.flags & ~FLAG_DELTA) return fail(`unknown flags ${h.flags}`);
    const delta = (h.flags & FLAG_DELTA) !== 0;
    if (delta && h.method === METHOD_RAW) return fail('delta flag on a raw message');
    if (h.bits > (h.method === METHOD_BAND ? MAX_BITS : 0))
      return fail(`bits ${h.bits} out of range for method ${h.method}`);
    if (h.reserved0 || h.reserved1) return fail('reserved field not zero');
    if (h.stampNsec >= 1e9) return fail('stamp nanoseconds out of range');
    for (const o of h.origin)
      if (!Number.isFinite(o) || Math.abs(o) > MAX_ABS_ORIGIN)
        return fail('origin not finite or beyond 1e4 m');
    if (!Number.isFinite(h.voxelSize) || !(h.voxelSize > 0) || h.voxelSize > MAX_VOXEL_SIZE)
      return fail('voxel size not finite or outside (0, 1] m');
    for (const d of h.dims)
      if (d < 1 || d > MAX_SIDE) return fail('dims out of range (1..256 per axis)');
    const [nx, ny, nz] = h.dims;
    const n = nx * ny * nz; // <= 2^24
    if (h.isoByte < 1 || h.isoByte > 254) return fail('iso byte out of range (1..254)');
    if (!delta && (h.referenceSequence || h.shift[0] || h.shift[1] || h.shift[2]))
      return fail('reference fields set in a key frame');
    for (const s of h.shift) if (Math.abs(s) > MAX_SHIFT) return fail('shift out of range');
    let tables = 0;
    if (h.method === METHOD_RAW) {
      if (h.bandCount || h.maskBytes) return fail('band fields set in a raw message');
      if (h.rawSize !== n) return fail(`raw size ${h.rawSize} != voxel count ${n}`);
    } else {
      tables = tableBytes(h.bits);
      if (h.bandCount > n) return fail('band count exceeds voxel count');
      if (h.maskBytes > 4 * n) return fail('mask section too large');
      if (tables + h.maskBytes + codeBytes(h.bandCount, h.bits) !== h.rawSize)
        return fail('section sizes do not add up to the raw size');
    }
    let ref = null;
    if (delta) {
      ref = this.#refs.find((r) => r.target === h.targetId) ?? null;
      if (!ref)
        return fail(`missing reference frame: no earlier frame of target ${h.targetId}`);
      if (ref.sequence !== h.referenceSequence)
        return fail(
          `missing reference frame: target ${h.targetId} needs sequence ` +
            `${h.referenceSequence}, last decoded is ${ref.sequence}`,
        );
      if (
        ref.dims.some((d, i) => d !== h.dims[i]) ||
        ref.voxelSize !== h.voxelSize ||
        ref.isoByte !== h.isoByte
      )
        return fail('reference frame mismatch (dims, voxel size or iso byte differ)');
    }

    // ---- payload: exactly one zstd frame of the announced size ----
    const payload = bytes.subarray(HEADER_SIZE, HEADER_SIZE + h.payloadSize);
    const zh = zstdFrameHeader(payload);
    if (!zh) return fail('zstd: invalid frame header');
    if (zh.contentSize === CONTENT_UNKNOWN) return fail('zstd: frame has no content size');
    if (zh.contentSize !== h.rawSize)
      return fail(`zstd: content size ${zh.contentText} != raw size ${h.rawSize}`);
    const frame = zstdFrameSize(payload, zh);
    if (frame.error) return fail(`zstd: ${frame.error}`);
    if (frame.size !== h.payloadSize) return fail('zstd: payload is not exactly one frame');
    const raw = new Uint8Array(h.rawSize); // method 0: the volume itself
    const zstdError = zstdDecompress(payload, zh, frame, raw);
    if (zstdError) return fail(`zstd: ${zstdError}`);

    // ---- volume ----
    const above = this.#scratch('above', n);
    let volume;
    if (h.method === METHOD_RAW) {
      volume = raw;
      for (let i = 0; i < n; ++i) above[i] = volume[i] > h.isoByte ? 0xff : 0;
    } else {
      volume = this.#decodeBand(h, raw, tables, above, ref);
      if (typeof volume === 'string') return fail(volume);
    }

    // This frame becomes the target's reference (its mask buffer swapped in, as in C++).
    const r = this.#slot(h.targetId);
    r.target = h.targetId;
    r.sequence = h.sequence;
    r.dims = [...h.dims]; // not the frame's array: the caller may change that
    r.voxelSize = h.voxelSize;
    r.isoByte = h.isoByte;
    r.lastUse = ++this.#tick;
    [r.above, this.#buf.above] = [above, r.above];

    return {
      ok: true,
      frame: {
        targetId: h.targetId,
        sequence: h.sequence,
        stampSec: h.stampSec,
        stampNsec: h.stampNsec,
        origin: h.origin,
        voxelSize: h.voxelSize,
        dims: h.dims,
        isoByte: h.isoByte,
        data: volume,
      },
      info: {
        method: h.method,
        bits: h.bits,
        keyFrame: !delta,
        sequence: h.sequence,
        referenceSequence: h.referenceSequence,
        shift: h.shift,
        messageBytes: size,
        payloadBytes: h.payloadSize,
        rawBytes: h.rawSize,
        maskBytes: h.maskBytes,
        bandSamples: h.bandCount,
      },
    };
  }

  // Method 1: mask from the residual gaps and the prediction, then the band and its codes. Fills
  // `above`; returns the volume or a reason.
  #decodeBand(h, raw, tables, above, ref) {
    const [nx, ny, nz] = h.dims;
    const n = nx * ny * nz;
    const bits = h.bits;
    const L = levelsFor(bits);
    for (let c = 0; c < CONTEXTS; ++c)
      for (let j = 0; j < L; ++j) {
        const v = raw[c * L + j];
        if (c >= 6 !== v > h.isoByte)
          return `table value ${v} on the wrong side of the iso for context ${c}`;
      }
    // Mask: the residual samples from the gaps (strictly increasing, so at most n of them; the
    // band index list holds them until the band is classified), then the prediction flipped at
    // them. The mask is kept as 0 / 255 bytes: the volume starts as a copy of it.
    const maskEnd = tables + h.maskBytes;
    this.#reserveBand(n);
    const residual = this.#bandIndex;
    let count = 0;
    let next = 0;
    for (let p = tables; p < maskEnd; ) {
      const v = readVarint(raw, p, maskEnd);
      if (!v) return 'mask: bad varint';
      const i = next + v[0];
      if (i >= n) return 'mask: sample index out of range';
      residual[count++] = i;
      next = i + 1;
      p = v[1];
    }
    if (ref) {
      shiftedMask(ref.above, nx, ny, nz, h.shift[0], h.shift[1], h.shift[2], above);
      for (let j = 0; j < count; ++j) above[residual[j]] ^= 0xff;
    } else {
      const slice = nx * ny; // each slice predicts the next, in z order
      above.fill(0, 0, slice);
      for (let z = 0, j = 0; z < nz; ++z) {
        if (z > 0) above.copyWithin(z * slice, (z - 1) * slice, z * slice);
        for (const end = (z + 1) * slice; j < count && residual[j] < end; ++j)
          above[residual[j]] ^= 0xff;
      }
    }
    const band = this.#classifyBand(above, nx, ny, nz);
    if (band !== h.bandCount)
      return `band count mismatch: mask gives ${band}, header says ${h.bandCount}`;
    const k = codesPerByte(bits);
    if (k > 0 && bits * k < 8) {
      // padding bits of every code byte must be zero
      const pad = (0xff << (bits * k)) & 0xff;
      const end = maskEnd + codeBytes(band, bits);
      for (let b = maskEnd; b < end; ++b)
        if (raw[b] & pad) return 'codes: nonzero padding bits';
    }
    if (k > 0 && band % k) {
      // unused code slots of the last byte must be zero
      const used = (1 << (bits * (band % k))) - 1;
      if (raw[maskEnd + Math.floor(band / k)] & ~used & 0xff)
        return 'codes: nonzero unused slots in the last byte';
    }
    const volume = above.slice();
    const codeMask = (1 << bits) - 1;
    const index = this.#bandIndex;
    const context = this.#bandContext;
    for (let j = 0; j < band; ++j) {
      const code = k ? (raw[maskEnd + Math.floor(j / k)] >> (bits * (j % k))) & codeMask : 0;
      volume[index[j]] = raw[(context[j] - 1) * L + code];
    }
    return volume;
  }

  // Samples with a 6-neighbour on the other side of the iso (outside the volume counts as below):
  // their raster indices and contexts 1 + side * 6 + (opposite neighbours - 1) into the band
  // lists (reserved by the caller); returns how many.
  #classifyBand(above, nx, ny, nz) {
    // A padded copy makes every neighbour readable, and its zeros are exactly the "outside is
    // below" rule: rows of 4 zero bytes, the samples and 1-4 zero bytes (4-byte aligned, so a
    // row is checked for above samples a word at a time), a ring of zero rows and slices.
    const px = (nx + 8) & ~3;
    const ry = ny + 2;
    const pxy = px * ry;
    const padded = this.#scratch('padded', pxy * (nz + 2));
    const words = new Uint32Array(padded.buffer, 0, padded.length / 4);
    const occupied = this.#scratch('occupied', ry * (nz + 2)); // per padded row: any above
    padded.fill(0);
    occupied.fill(0);
    for (let z = 0; z < nz; ++z)
      for (let y = 0; y < ny; ++y) {
        const src = nx * (y + ny * z);
        const dst = (z + 1) * pxy + (y + 1) * px + 4;
        padded.set(above.subarray(src, src + nx), dst);
        let any = 0;
        for (let w = dst >> 2, end = (dst + nx + 3) >> 2; w < end; ++w) any |= words[w];
        occupied[y + 1 + ry * (z + 1)] = any ? 1 : 0;
      }
    const index = this.#bandIndex;
    const context = this.#bandContext;
    let band = 0;
    for (let z = 0; z < nz; ++z)
      for (let y = 0; y < ny; ++y) {
        const r = y + 1 + ry * (z + 1);
        // Rows whose samples and 6-neighbours are all below hold no band sample.
        if (!(occupied[r] | occupied[r - 1] | occupied[r + 1] | occupied[r - ry] | occupied[r + ry]))
          continue;
        const row = (z + 1) * pxy + (y + 1) * px + 4;
        const out = nx * (y + ny * z);
        for (let x = 0; x < nx; ++x) {
          const c = row + x;
          const u = padded[c];
          const k =
            ((u ^ padded[c - 1]) +
              (u ^ padded[c + 1]) +
              (u ^ padded[c - px]) +
              (u ^ padded[c + px]) +
              (u ^ padded[c - pxy]) +
              (u ^ padded[c + pxy])) /
            255;
          if (k) {
            index[band] = out + x;
            context[band] = (u & 1) * 6 + k;
            ++band;
          }
        }
      }
    return band;
  }

  // Band lists for n samples.
  #reserveBand(n) {
    if (this.#bandIndex.length >= n) return;
    this.#bandIndex = new Int32Array(n);
    this.#bandContext = new Uint8Array(n);
  }

  // The scratch byte array `name` with n elements (contents unspecified).
  #scratch(name, n) {
    if (this.#buf[name]?.length !== n) this.#buf[name] = new Uint8Array(n);
    return this.#buf[name];
  }

  // The reference slot for `target`: its own, a free one, or the least recently used.
  #slot(target) {
    const own = this.#refs.find((r) => r.target === target);
    if (own) return own;
    if (this.#refs.length < MAX_REFERENCES) {
      const r = { above: null };
      this.#refs.push(r);
      return r;
    }
    return this.#refs.reduce((oldest, r) => (r.lastUse < oldest.lastUse ? r : oldest));
  }
}

// Header fields as on the wire (offsets in hand_stream_codec.h); no checks.
function readHeader(bytes) {
  const v = new DataView(bytes.buffer, bytes.byteOffset, HEADER_SIZE);
  return {
    method: v.getUint8(5),
    flags: v.getUint8(6),
    bits: v.getUint8(7),
    targetId: v.getUint32(8, true),
    sequence: v.getUint32(12, true),
    stampSec: v.getUint32(16, true),
    stampNsec: v.getUint32(20, true),
    origin: [v.getFloat64(24, true), v.getFloat64(32, true), v.getFloat64(40, true)],
    voxelSize: v.getFloat64(48, true),
    dims: [v.getUint16(56, true), v.getUint16(58, true), v.getUint16(60, true)],
    isoByte: v.getUint8(62),
    reserved0: v.getUint8(63),
    referenceSequence: v.getUint32(64, true),
    shift: [v.getInt16(68, true), v.getInt16(70, true), v.getInt16(72, true)],
    reserved1: v.getUint16(74, true),
    bandCount: v.getUint32(76, true),
    maskBytes: v.getUint32(80, true),
    rawSize: v.getUint32(84, true),
    payloadSize: v.getUint32(88, true),
  };
}
