// The replay page's time lookups (web/replay/src/data.js) under node's test
// runner, without a browser: node --test tests/browser/data_test.mjs
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { frameIndexAt, sampleAt, nextSlip, previousSlip, mapAt } from '../../web/replay/src/data.js';

const frames = [{ t: 0.001 }, { t: 0.04 }, { t: 0.08 }, { t: 0.105 }, { t: 0.12 }];

test('the frame at a time is the last one at or before it', () => {
  assert.equal(frameIndexAt(frames, 0), 0);
  assert.equal(frameIndexAt(frames, 0.001), 0);
  assert.equal(frameIndexAt(frames, 0.0399), 0);
  assert.equal(frameIndexAt(frames, 0.105), 3);
  assert.equal(frameIndexAt(frames, 0.11), 3);
  assert.equal(frameIndexAt(frames, 5), 4);
  assert.equal(frameIndexAt([], 1), 0);
});

test('a sample holds its frame and the way to the next', () => {
  const s = sampleAt(frames, 0.06);
  assert.equal(s.index, 1);
  assert.equal(s.next.t, 0.08);
  assert.ok(Math.abs(s.alpha - 0.5) < 1e-9);
  const end = sampleAt(frames, 1);
  assert.equal(end.index, 4);
  assert.equal(end.alpha, 0);
});

test('next and previous slip skip the one at the present time', () => {
  const slips = [[0.105, 0.108, 2], [1.5, 1.6, 0], [2.0, 2.1, 1]];
  assert.deepEqual(nextSlip(slips, 0), slips[0]);
  assert.deepEqual(nextSlip(slips, 0.105), slips[1]);
  assert.equal(nextSlip(slips, 2.0), null);
  assert.deepEqual(previousSlip(slips, 2.0), slips[1]);
  assert.equal(previousSlip(slips, 0.105), null);
});

test('the map at a time holds each cell written by then, with its last write', () => {
  const writes = [[1.0, 0.625, 0.375, 0.25, 1], [2.0, 1.125, -0.375, 0.2, 1], [3.0, 0.625, 0.375, 0.27, 2]];
  assert.equal(mapAt(writes, 0.5).size, 0);
  assert.deepEqual([...mapAt(writes, 1.0).values()], [[0.625, 0.375, 0.25, 1]]);
  const later = mapAt(writes, 3.0);
  assert.equal(later.size, 2);
  assert.deepEqual(later.get('0.625,0.375'), [0.625, 0.375, 0.27, 2]);
  assert.deepEqual(later.get('1.125,-0.375'), [1.125, -0.375, 0.2, 1]);
  assert.equal(mapAt([], 3.0).size, 0);
  // Forgotten max_age after its last write.
  const aged = mapAt(writes, 62.5, 60);
  assert.deepEqual([...aged.keys()], ['0.625,0.375']);
  assert.equal(mapAt(writes, 63.5, 60).size, 0);
});
