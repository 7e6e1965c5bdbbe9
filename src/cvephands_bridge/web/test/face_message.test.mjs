// Face video messages (src/face_message.js) against the layout of face_video.h.
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { isFaceMessage, parseFaceMessage } from '../src/face_message.js';
import { crc32 } from '../src/hand_decoder.js';

// A message as face_video.h lays it out, around `jpeg` (any bytes: the parser does not decode).
function faceMessage({ sec = 7, nsec = 500000000, width = 128, height = 96, jpeg = new Uint8Array([0xff, 0xd8, 1, 2, 3, 0xff, 0xd9]) } = {}) {
  const m = new Uint8Array(24 + jpeg.length + 4);
  const v = new DataView(m.buffer);
  m.set([0x43, 0x56, 0x56, 0x46, 1, 1], 0);
  v.setUint32(8, sec, true);
  v.setUint32(12, nsec, true);
  v.setUint16(16, width, true);
  v.setUint16(18, height, true);
  v.setUint32(20, jpeg.length, true);
  m.set(jpeg, 24);
  v.setUint32(24 + jpeg.length, crc32(m.subarray(0, 24 + jpeg.length)), true);
  return m;
}

test('a face message parses to its stamp, size and JPEG bytes', () => {
  const m = faceMessage();
  assert.ok(isFaceMessage(m));
  const f = parseFaceMessage(m);
  assert.ok(f.ok, f.reason);
  assert.equal(f.stampMs, 7500);
  assert.equal(f.width, 128);
  assert.equal(f.height, 96);
  assert.deepEqual([...f.jpeg], [0xff, 0xd8, 1, 2, 3, 0xff, 0xd9]);
});

test('hand messages are not face messages', () => {
  assert.ok(!isFaceMessage(new Uint8Array([0x43, 0x56, 0x48, 0x53, 1, 1])));  // "CVHS"
  assert.ok(!isFaceMessage(new Uint8Array([0x43, 0x56])));
});

test('every malformed face message is rejected with its reason', () => {
  const good = faceMessage();
  const cases = [
    [(m) => { m[4] = 2; }, 'version'],
    [(m) => { m[5] = 9; }, 'format'],
    [(m) => { m[6] = 1; }, 'reserved'],
    [(m) => { m[15] = 0xff; }, 'nanoseconds'],
    [(m) => { m[16] = 0; m[17] = 0; }, 'picture size'],
    [(m) => { m[22] = 0x10; }, 'JPEG size'],
    [(m) => { m[26] ^= 1; }, 'checksum'],
  ];
  for (const [mutate, reason] of cases) {
    const m = good.slice();
    mutate(m);
    const f = parseFaceMessage(m);
    assert.ok(!f.ok, reason);
    assert.match(f.reason, new RegExp(reason));
  }
  assert.match(parseFaceMessage(good.subarray(0, 20)).reason, /truncated/);
  assert.match(parseFaceMessage(good.subarray(0, good.length - 1)).reason, /size does not match/);
  assert.match(parseFaceMessage(new Uint8Array(40)).reason, /magic/);
});
