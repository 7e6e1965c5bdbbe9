// Hand stream decoder: checksums and varints, round trips of messages built here from the wire
// format's description (hand_stream_codec.h; zstd frames of raw blocks, since fzstd only
// decompresses), every rejection with its reason, reference bookkeeping, and never throwing on
// mutated input. Real encoder output is compared with the C++ decoder by cross_check.mjs.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { HandStreamDecoder, crc32, readVarint, xxh64Low32 } from '../src/hand_decoder.js';
import { random } from './random.mjs';

const ISO = 153;
const F = {
  method: 5, flags: 6, bits: 7, target: 8, sequence: 12, nsec: 20, origin: 24, voxel: 48,
  dims: 56, iso: 62, reserved0: 63, refSequence: 64, shift: 68, reserved1: 74, bandCount: 76,
  maskBytes: 80, rawSize: 84, payloadSize: 88, payload: 92,
};

// ---- a reference encoder, from the format's description ------------------------------------

// A ball with a 2-voxel probability ramp and +-20 noise, in a box of odd dims (axis mix-ups show).
function ballFrame(dims = [17, 14, 12], centre = [8.3, 6.9, 5.6], radius = 4.5, seed = 1) {
  const rnd = random(seed);
  const [nx, ny, nz] = dims;
  const data = new Uint8Array(nx * ny * nz);
  for (let z = 0, i = 0; z < nz; ++z)
    for (let y = 0; y < ny; ++y)
      for (let x = 0; x < nx; ++x, ++i) {
        const sd =
          Math.hypot(x + 0.5 - centre[0], y + 0.5 - centre[1], z + 0.5 - centre[2]) - radius;
        const p = Math.min(1, Math.max(0, 0.5 - sd / 2));
        data[i] = Math.min(255, Math.max(0, Math.round(255 * p + 40 * (rnd() - 0.5))));
      }
  const origin = [-0.25, 0.5, 0.125];
  return { targetId: 3, stampSec: 12, stampNsec: 345, origin, voxelSize: 0.004, dims, data };
}

const product = (d) => d[0] * d[1] * d[2];
const aboveOf = (data) => data.map((v) => (v > ISO ? 1 : 0));

// mask(x + s) with 0 outside.
function shifted(mask, [nx, ny, nz], [sx, sy, sz]) {
  const out = new Uint8Array(nx * ny * nz);
  for (let z = 0, i = 0; z < nz; ++z)
    for (let y = 0; y < ny; ++y)
      for (let x = 0; x < nx; ++x, ++i) {
        const [a, b, c] = [x + sx, y + sy, z + sz];
        if (a >= 0 && a < nx && b >= 0 && b < ny && c >= 0 && c < nz)
          out[i] = mask[a + nx * (b + ny * c)];
      }
  return out;
}

// Band samples (a 6-neighbour on the other side, outside = below) and their contexts 0..11.
function bandOf(above, [nx, ny, nz]) {
  const at = (x, y, z) =>
    x < 0 || y < 0 || z < 0 || x >= nx || y >= ny || z >= nz ? 0 : above[x + nx * (y + ny * z)];
  const index = [];
  const context = [];
  for (let z = 0, i = 0; z < nz; ++z)
    for (let y = 0; y < ny; ++y)
      for (let x = 0; x < nx; ++x, ++i) {
        const u = above[i];
        const k = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]].filter(
          ([a, b, c]) => at(x + a, y + b, z + c) !== u,
        ).length;
        if (k) index.push(i), context.push(u * 6 + k - 1);
      }
  return { index, context };
}

function varint(v) {
  const out = [];
  for (; v >= 0x80; v >>>= 7) out.push((v & 0x7f) | 0x80);
  out.push(v);
  return out;
}

// One zstd frame of raw blocks (RFC 8878): single segment with a 4-byte content size unless told
// otherwise (window: a window descriptor byte).
function zstdFrame(content, { contentSize = true, checksum = false, dictId = 0, window = 0 } = {}) {
  const single = contentSize && !window;
  const fhd =
    (contentSize ? 0x80 : 0) | (single ? 0x20 : 0) | (checksum ? 4 : 0) | (dictId ? 3 : 0);
  const head = [0x28, 0xb5, 0x2f, 0xfd, fhd];
  if (!single) head.push(window);
  if (dictId) head.push(...u32le(dictId));
  if (contentSize) head.push(...u32le(content.length));
  const parts = [new Uint8Array(head)];
  const max = 1 << 17;
  for (let p = 0; ; p += max) {
    const part = content.subarray(p, p + max);
    const last = p + max >= content.length;
    const bh = (part.length << 3) | (last ? 1 : 0); // block type 0: raw
    parts.push(new Uint8Array([bh & 0xff, (bh >> 8) & 0xff, bh >> 16]), part);
    if (last) break;
  }
  if (checksum) parts.push(new Uint8Array(u32le(xxh64Low32(content))));
  const out = new Uint8Array(parts.reduce((n, q) => n + q.length, 0));
  parts.reduce((at, q) => (out.set(q, at), at + q.length), 0);
  return out;
}
const u32le = (v) => [v & 0xff, (v >>> 8) & 0xff, (v >>> 16) & 0xff, v >>> 24];

// Header + payload + CRC; fields as in the wire format table.
function assemble(h, raw, payload = zstdFrame(raw)) {
  const m = new Uint8Array(F.payload + payload.length + 4);
  const v = new DataView(m.buffer);
  m.set([0x43, 0x56, 0x48, 0x53, 1, h.method, h.flags ?? 0, h.bits ?? 0]);
  v.setUint32(F.target, h.targetId, true);
  v.setUint32(F.sequence, h.sequence ?? 0, true);
  v.setUint32(16, h.stampSec, true);
  v.setUint32(F.nsec, h.stampNsec, true);
  h.origin.forEach((o, i) => v.setFloat64(F.origin + 8 * i, o, true));
  v.setFloat64(F.voxel, h.voxelSize, true);
  h.dims.forEach((d, i) => v.setUint16(F.dims + 2 * i, d, true));
  m[F.iso] = ISO;
  v.setUint32(F.refSequence, h.refSequence ?? 0, true);
  (h.shift ?? [0, 0, 0]).forEach((s, i) => v.setInt16(F.shift + 2 * i, s, true));
  v.setUint32(F.bandCount, h.bandCount ?? 0, true);
  v.setUint32(F.maskBytes, h.maskBytes ?? 0, true);
  v.setUint32(F.rawSize, raw.length, true);
  v.setUint32(F.payloadSize, payload.length, true);
  m.set(payload, F.payload);
  return fixCrc(m);
}
function fixCrc(m) {
  new DataView(m.buffer, m.byteOffset).setUint32(m.length - 4, crc32(m, m.length - 4), true);
  return m;
}
function withField(m, offset, value, bytes) {
  const c = m.slice();
  for (let i = 0; i < bytes; ++i) c[offset + i] = Math.floor(value / 2 ** (8 * i)) & 0xff;
  return fixCrc(c);
}
function withFloat(m, offset, value) {
  const c = m.slice();
  new DataView(c.buffer).setFloat64(offset, value, true);
  return fixCrc(c);
}

// A band message of `frame` (key frame, or a delta from ref = { above, sequence } moved by shift)
// and the volume the format says it decodes to.
function bandMessage(frame, { bits = 2, sequence = 0, ref = null, shift = [0, 0, 0] } = {}) {
  const { dims, data } = frame;
  const n = product(dims);
  const above = aboveOf(data);
  const prediction = ref ? shifted(ref.above, dims, shift) : shifted(above, dims, [0, 0, -1]);
  const L = 1 << bits;
  // Levels evenly spread over each side of the iso; a value's code is its nearest level.
  const step = (span) => (j) => Math.round((j * span) / Math.max(1, L - 1));
  const level = (side, j) => (side ? ISO + 1 + step(254 - ISO)(j) : step(ISO)(j));
  const tables = [];
  for (let c = 0; c < 12; ++c) for (let j = 0; j < L; ++j) tables.push(level(c >= 6 ? 1 : 0, j));
  const mask = [];
  for (let i = 0, next = 0; i < n; ++i)
    if (above[i] !== prediction[i]) mask.push(...varint(i - next)), (next = i + 1);
  const { index, context } = bandOf(above, dims);
  const k = bits ? Math.floor(8 / bits) : 0;
  const codes = new Array(k ? Math.ceil(index.length / k) : 0).fill(0);
  const expected = above.map((a) => (a ? 255 : 0));
  index.forEach((i, j) => {
    const side = context[j] >= 6 ? 1 : 0;
    let code = 0;
    const miss = (l) => Math.abs(level(side, l) - data[i]);
    for (let l = 1; l < L; ++l) if (miss(l) < miss(code)) code = l;
    if (k) codes[Math.floor(j / k)] |= code << (bits * (j % k));
    expected[i] = tables[context[j] * L + code];
  });
  const raw = new Uint8Array([...tables, ...mask, ...codes]);
  const h = { ...frame, method: 1, bits, sequence };
  Object.assign(h, { bandCount: index.length, maskBytes: mask.length });
  if (ref) Object.assign(h, { flags: 1, refSequence: ref.sequence, shift });
  return { message: assemble(h, raw), expected, above, raw, h };
}

function decodeOk(decoder, message) {
  const r = decoder.decode(message);
  assert.ok(r.ok, r.reason);
  return r;
}

// ---- checksums and varints -------------------------------------------------------------------

test('CRC-32 (zlib polynomial) and XXH64 check values', () => {
  const ascii = (s) => new TextEncoder().encode(s);
  assert.equal(crc32(ascii('123456789')), 0xcbf43926);
  assert.equal(crc32(new Uint8Array(0)), 0);
  assert.equal(crc32(ascii('123456789xyz'), 9), 0xcbf43926); // only [0, end)
  // Low halves of XXH64("") = ef46db3751d8e999 and XXH64("abc") = 44bc2cf5ad770999.
  assert.equal(xxh64Low32(new Uint8Array(0)), 0x51d8e999);
  assert.equal(xxh64Low32(ascii('abc')), 0xad770999);
});

test('varints: 1 to 4 bytes, end respected, longer ones rejected', () => {
  const read = (bytes, end = bytes.length) => readVarint(new Uint8Array(bytes), 0, end);
  assert.deepEqual(read([0x00]), [0, 1]);
  assert.deepEqual(read([0x7f, 0x55]), [127, 1]);
  assert.deepEqual(read([0x80, 0x01]), [128, 2]);
  assert.deepEqual(read([0xff, 0xff, 0xff, 0x7f]), [2 ** 28 - 1, 4]);
  assert.deepEqual(read(varint(2 ** 24 - 1)), [2 ** 24 - 1, 4]);
  assert.equal(read([0x80, 0x80, 0x80, 0x80, 0x00]), null); // a 5th byte
  assert.equal(read([0x80, 0x80]), null); // unterminated
  assert.equal(read([0x80, 0x01], 1), null); // terminated only past the end
  assert.equal(read([]), null);
});

// ---- round trips -----------------------------------------------------------------------------

test('band key and delta frames of every code width decode as the format says', () => {
  for (const bits of [0, 1, 2, 3, 5, 8]) {
    const decoder = new HandStreamDecoder();
    const a = ballFrame();
    const key = bandMessage(a, { bits });
    const r = decodeOk(decoder, key.message);
    assert.deepEqual(r.frame.data, key.expected, `bits ${bits}`);
    assert.deepEqual(
      { ...r.frame, data: null },
      {
        targetId: 3, sequence: 0, stampSec: 12, stampNsec: 345, origin: a.origin,
        voxelSize: 0.004, dims: a.dims, isoByte: ISO, data: null,
      },
    );
    assert.deepEqual(r.info, {
      method: 1, bits, keyFrame: true, sequence: 0, referenceSequence: 0, shift: [0, 0, 0],
      messageBytes: key.message.length, payloadBytes: key.message.length - 96,
      rawBytes: key.raw.length,
      maskBytes: key.h.maskBytes, bandSamples: key.h.bandCount,
    });
    // The next frame, predicted from the previous mask moved by (1, -2, 1) voxels.
    const b = ballFrame(a.dims, [9.1, 5.2, 6.4], 4.7, 2);
    const ref = { above: key.above, sequence: 0 };
    const delta = bandMessage(b, { bits, sequence: 1, ref, shift: [1, -2, 1] });
    const rd = decodeOk(decoder, delta.message);
    assert.deepEqual(rd.frame.data, delta.expected, `bits ${bits} delta`);
    assert.equal(rd.info.keyFrame, false);
    assert.deepEqual(rd.info.shift, [1, -2, 1]);
    assert.ok(delta.h.maskBytes > 0 && delta.h.bandCount > 0);
  }
});

test('raw messages decode to their bytes, in any number of zstd blocks, with a checksum', () => {
  const f = ballFrame([70, 50, 40]); // 140000 bytes: two raw blocks
  const raw = assemble({ ...f, method: 0 }, f.data, zstdFrame(f.data, { checksum: true }));
  const r = decodeOk(new HandStreamDecoder(), raw);
  assert.deepEqual(r.frame.data, f.data);
  assert.equal(r.info.method, 0);
  // ArrayBuffers (WebSocket binaryType 'arraybuffer') are read too, and views at any offset.
  assert.ok(new HandStreamDecoder().decode(raw.buffer).ok);
  const inside = new Uint8Array(raw.length + 3);
  inside.set(raw, 3);
  assert.deepEqual(decodeOk(new HandStreamDecoder(), inside.subarray(3)).frame.data, f.data);
});

// ---- rejections --------------------------------------------------------------------------------

test('every rejection has its reason, and rejections keep the references', () => {
  const a = ballFrame();
  const n = product(a.dims);
  const key = bandMessage(a, { bits: 3 }); // 2 codes per byte: 2 padding bits
  const ref = { above: key.above, sequence: 0 };
  const next = ballFrame(a.dims, [8.5, 7.2, 5.6], 4.6, 5);
  const delta = bandMessage(next, { bits: 3, sequence: 1, ref });
  const raw = assemble({ ...a, method: 0 }, a.data);
  let oneBit;
  for (let s = 1; !oneBit; ++s) {
    const m = bandMessage(ballFrame(a.dims, [8, 7, 6], 4.5, s), { bits: 1 });
    if (m.h.bandCount % 8) oneBit = m; // unused code slots in the last byte
  }
  const tables = 12 * 8;
  const mask = key.h.maskBytes;
  const rawEdit = (base, edit) => {
    const r = [...base.raw];
    const h = { ...base.h };
    edit(r, h);
    return assemble(h, new Uint8Array(r));
  };
  const payloadEdit = (base, edit) => {
    const p = [...base.message.subarray(F.payload, base.message.length - 4)];
    edit(p);
    return assemble(base.h, base.raw, new Uint8Array(p));
  };
  // A frame claiming the key's content size around a block one byte shorter or longer.
  const misSized = (d) => {
    const z = zstdFrame(d > 0 ? new Uint8Array([...key.raw, 0]) : key.raw.subarray(0, -1));
    z.set(u32le(key.raw.length), 5);
    return assemble(key.h, key.raw, z);
  };
  const primed = () => {
    const d = new HandStreamDecoder();
    decodeOk(d, key.message);
    return d;
  };
  const cases = [
    ['short', key.message.subarray(0, 95), 'truncated header: 95 bytes, a message has at least 96'],
    [
      'magic',
      fixCrc(Object.assign(key.message.slice(), { 0: 0x58 })),
      'bad magic (not a hand stream message)',
    ],
    ['version', withField(key.message, 4, 2, 1), 'unsupported version 2 (this decoder reads 1)'],
    ['truncated', key.message.subarray(0, key.message.length - 1), 'size mismatch: header says'],
    [
      'bit flip',
      Object.assign(key.message.slice(), { [F.payload + 3]: key.message[F.payload + 3] ^ 0x10 }),
      'checksum mismatch',
    ],
    ['method', withField(key.message, F.method, 2, 1), 'unknown method 2'],
    ['flags', withField(key.message, F.flags, 2, 1), 'unknown flags 2'],
    ['raw delta', withField(raw, F.flags, 1, 1), 'delta flag on a raw message'],
    ['bits', withField(key.message, F.bits, 9, 1), 'bits 9 out of range for method 1'],
    ['raw bits', withField(raw, F.bits, 1, 1), 'bits 1 out of range for method 0'],
    ['reserved0', withField(key.message, F.reserved0, 1, 1), 'reserved field not zero'],
    ['reserved1', withField(key.message, F.reserved1, 1, 2), 'reserved field not zero'],
    ['nsec', withField(key.message, F.nsec, 1e9, 4), 'stamp nanoseconds out of range'],
    ['origin nan', withFloat(key.message, F.origin + 8, NaN), 'origin not finite or beyond 1e4 m'],
    ['origin far', withFloat(key.message, F.origin, -1e5), 'origin not finite'],
    ['voxel 0', withFloat(key.message, F.voxel, 0), 'voxel size not finite or outside (0, 1] m'],
    ['voxel inf', withFloat(key.message, F.voxel, Infinity), 'voxel size'],
    ['voxel 2', withFloat(key.message, F.voxel, 2), 'voxel size'],
    ['dims 0', withField(key.message, F.dims + 2, 0, 2), 'dims out of range (1..256 per axis)'],
    ['dims 257', withField(key.message, F.dims + 4, 257, 2), 'dims out of range'],
    ['iso 0', withField(key.message, F.iso, 0, 1), 'iso byte out of range (1..254)'],
    ['iso 255', withField(key.message, F.iso, 255, 1), 'iso byte out of range'],
    ['key ref', withField(key.message, F.refSequence, 5, 4), 'reference fields set in a key frame'],
    ['key shift', withField(key.message, F.shift, 1, 2), 'reference fields set in a key frame'],
    ['shift', withField(delta.message, F.shift + 2, 0x10000 - 300, 2), 'shift out of range'],
    ['raw band', withField(raw, F.bandCount, 1, 4), 'band fields set in a raw message'],
    ['raw size', withField(raw, F.rawSize, n + 1, 4), `raw size ${n + 1} != voxel count ${n}`],
    ['band > n', withField(key.message, F.bandCount, n + 1, 4), 'band count exceeds voxel count'],
    ['mask > 4n', withField(key.message, F.maskBytes, 4 * n + 1, 4), 'mask section too large'],
    [
      'sections',
      withField(key.message, F.maskBytes, mask + 1, 4),
      'section sizes do not add up to the raw size',
    ],
    ['no reference', delta.message, 'missing reference frame: no earlier frame of target 3'],
    [
      'wrong sequence',
      withField(delta.message, F.refSequence, 7, 4),
      'missing reference frame: target 3 needs sequence 7, last decoded is 0',
      primed,
    ],
    [
      'reference mismatch',
      withFloat(delta.message, F.voxel, 0.005),
      'reference frame mismatch (dims, voxel size or iso byte differ)',
      primed,
    ],
    // zstd layer
    ['zstd header', payloadEdit(key, (p) => (p[0] ^= 0xff)), 'zstd: invalid frame header'],
    ['zstd reserved bit', payloadEdit(key, (p) => (p[4] |= 0x08)), 'zstd: invalid frame header'],
    [
      'zstd no size',
      assemble(key.h, key.raw, zstdFrame(key.raw, { contentSize: false })),
      'zstd: frame has no content size',
    ],
    [
      'zstd size',
      assemble(key.h, key.raw, zstdFrame(new Uint8Array([...key.raw, 0]))),
      `zstd: content size ${key.raw.length + 1} != raw size ${key.raw.length}`,
    ],
    [
      'zstd skippable',
      assemble(key.h, key.raw, new Uint8Array([0x50, 0x2a, 0x4d, 0x18, 0, 0, 0, 0])),
      `zstd: content size 0 != raw size`,
    ],
    ['zstd truncated', payloadEdit(key, (p) => p.pop()), 'zstd: Src size is incorrect'],
    [
      'zstd two frames',
      payloadEdit(key, (p) => p.push(...zstdFrame(new Uint8Array([1, 2, 3])))),
      'zstd: payload is not exactly one frame',
    ],
    ['zstd block type', payloadEdit(key, (p) => (p[9] |= 6)), 'zstd: Data corruption detected'],
    ['zstd short block', misSized(-1), 'zstd: Data corruption detected'],
    ['zstd long block', misSized(1), 'zstd: Destination buffer is too small'],
    [
      'zstd checksum',
      payloadEdit(
        { ...key, message: assemble(key.h, key.raw, zstdFrame(key.raw, { checksum: true })) },
        (p) => (p[p.length - 1] ^= 1),
      ),
      "zstd: Restored data doesn't match checksum",
    ],
    [
      'zstd dictionary',
      assemble(key.h, key.raw, zstdFrame(key.raw, { dictId: 7 })),
      'zstd: Dictionary mismatch',
    ],
    [
      'zstd window',
      assemble(key.h, key.raw, zstdFrame(key.raw, { window: 10 << 3 })),
      'zstd: window larger than the content',
    ],
    // behind zstd
    [
      'table side',
      rawEdit(key, (r) => (r[0] = 200)),
      'table value 200 on the wrong side of the iso for context 0',
    ],
    [
      'table side above',
      rawEdit(key, (r) => (r[6 * 8] = 100)),
      'table value 100 on the wrong side of the iso for context 6',
    ],
    ['varint', rawEdit(key, (r) => (r[tables + mask - 1] |= 0x80)), 'mask: bad varint'],
    [
      'varint long',
      rawEdit(key, (r, h) => {
        r.splice(tables, 0, 0x81, 0x80, 0x80, 0x80, 0x00);
        h.maskBytes += 5;
      }),
      'mask: bad varint',
    ],
    [
      'mask index',
      rawEdit(key, (r, h) => {
        r.splice(tables + mask, 0, ...varint(n));
        h.maskBytes += varint(n).length;
      }),
      'mask: sample index out of range',
    ],
    [
      'band count',
      rawEdit(key, (r, h) => { r.push(0); h.bandCount += 2; }),
      `band count mismatch: mask gives ${key.h.bandCount}, header says ${key.h.bandCount + 2}`,
    ],
    ['padding', rawEdit(key, (r) => (r[tables + mask] |= 0x40)), 'codes: nonzero padding bits'],
    [
      'unused slots',
      rawEdit(oneBit, (r) => (r[r.length - 1] |= 0x80)),
      'codes: nonzero unused slots in the last byte',
    ],
    ['not bytes', [1, 2, 3], 'not a Uint8Array'],
  ];
  for (const [name, message, reason, decoder = () => new HandStreamDecoder()] of cases) {
    const d = decoder();
    const r = d.decode(message);
    assert.equal(r.ok, false, `${name} was accepted`);
    assert.ok(r.reason.startsWith(reason), `${name}: "${r.reason}"`);
    if (decoder === primed)
      assert.deepEqual(decodeOk(d, delta.message).frame.data, delta.expected, name);
  }
  // The unmodified messages decode.
  assert.ok(new HandStreamDecoder().decode(raw).ok);
  assert.ok(new HandStreamDecoder().decode(oneBit.message).ok);
});

// ---- references ------------------------------------------------------------------------------

test('references: 16 most recently decoded targets; reset forgets them', () => {
  const d = new HandStreamDecoder();
  const deltas = [];
  for (let t = 0; t < 17; ++t) {
    const f = { ...ballFrame([10, 9, 8], [5, 4.5, 4], 3), targetId: 100 + t };
    const key = bandMessage(f);
    decodeOk(d, key.message);
    deltas.push(bandMessage(f, { sequence: 1, ref: { above: key.above, sequence: 0 } }).message);
  }
  // Target 100 was the least recently used when 116 arrived: its reference is gone.
  const missing = 'missing reference frame: no earlier frame of target';
  assert.equal(d.decode(deltas[0]).reason, `${missing} 100`);
  for (let t = 1; t < 17; ++t) decodeOk(d, deltas[t]);
  d.reset();
  assert.equal(d.decode(deltas[5]).reason, `${missing} 105`);
});

// ---- robustness ------------------------------------------------------------------------------

test('mutated messages are decoded or rejected, never thrown on', () => {
  const rnd = random(7);
  const key = bandMessage(ballFrame([12, 11, 10], [6, 5.5, 5], 3.5), { bits: 2 });
  const ref = { above: key.above, sequence: 0 };
  const delta = bandMessage(ballFrame([12, 11, 10], [6.5, 5.5, 5], 3.6, 3), { sequence: 1, ref });
  const d = new HandStreamDecoder();
  let accepted = 0;
  for (let i = 0; i < 3000; ++i) {
    const base = (i & 1 ? delta : key).message;
    let m = base.slice();
    const kind = i % 5;
    const at = (size) => Math.floor(rnd() * size);
    if (kind === 0) m[at(m.length)] ^= 1 << at(8); // the checksum catches it
    else if (kind === 1) m = m.subarray(0, at(m.length));
    else if (kind === 2) m = new Uint8Array(at(200)).map(() => at(256));
    else {
      // behind the checksum: header fields and payload bytes
      for (let k = 0; k < 1 + kind; ++k) m[at(m.length - 4)] = at(256);
      fixCrc(m);
    }
    if (i % 50 === 0) decodeOk(d, key.message); // a reference for the deltas now and then
    const r = d.decode(m);
    assert.equal(typeof r.ok, 'boolean');
    if (r.ok) {
      ++accepted;
      assert.equal(r.frame.data.length, product(r.frame.dims));
    } else {
      assert.ok(r.reason.length > 0);
    }
  }
  assert.ok(accepted < 3000);
});
