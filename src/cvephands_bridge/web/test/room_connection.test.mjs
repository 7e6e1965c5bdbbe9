// Reconnect back-off of the browser client (src/room_connection.js) against the rigs' bridge
// (include/cvephands_bridge/room/reconnect_backoff.h: 1, 2, 4, ... s up to 30 s).
import assert from 'node:assert/strict';
import { test } from 'node:test';

import { retryDelayMs } from '../src/room_connection.js';

test('retry delays double from 1 s up to 30 s', () => {
  assert.deepEqual([1, 2, 3, 4, 5, 6, 7, 50].map((n) => retryDelayMs(n)),
    [1000, 2000, 4000, 8000, 16000, 30000, 30000, 30000]);
});

test('retry delays take their own initial and maximum', () => {
  assert.equal(retryDelayMs(1, 500, 4000), 500);
  assert.equal(retryDelayMs(4, 500, 4000), 4000);
  assert.equal(retryDelayMs(0), 1000);  // before any failure: the initial wait
  assert.equal(retryDelayMs(1e9), 30000);  // no overflow to Infinity
});
