// The run's data as hyq_sim writes it into the page (sim_host/records/replay.cpp):
// looking up the frame at a time, and the slip events around a time.
// No drawing here.

// Index of the last frame at or before time t (0 before the first).
export function frameIndexAt(frames, t) {
  let lo = 0;
  let hi = frames.length - 1;
  if (hi < 0 || t <= frames[0].t) return 0;
  if (t >= frames[hi].t) return hi;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (frames[mid].t <= t) lo = mid;
    else hi = mid;
  }
  return lo;
}

// What is drawn at time t: the flags and forces of the last frame at or
// before t (kept at every change, so exact), and the positions between it
// and the next frame, linearly (alpha in [0, 1)).
export function sampleAt(frames, t) {
  const i = frameIndexAt(frames, t);
  const a = frames[i];
  const b = frames[Math.min(i + 1, frames.length - 1)];
  const span = b.t - a.t;
  const alpha = span > 0 ? Math.min(Math.max((t - a.t) / span, 0), 1) : 0;
  return { index: i, frame: a, next: b, alpha };
}

// The first true slip starting after time t (+1 ms), or null.
export function nextSlip(slips, t) {
  for (const s of slips) if (s[0] > t + 0.0005) return s;
  return null;
}

// The last true slip starting before time t (-1 ms), or null.
export function previousSlip(slips, t) {
  let found = null;
  for (const s of slips) if (s[0] < t - 0.0005) found = s;
  return found;
}

export function bit(mask, leg) {
  return (mask >> leg) & 1;
}

// The controller's friction map at time t from its writes [t, x, y, mu,
// count] (in time order): each cell written at or before t and not older
// than maxAge [s] then (the controller forgets it after that), with its
// last write, as [x, y, mu, count] keyed by "x,y".
export function mapAt(writes, t, maxAge = Infinity) {
  const cells = new Map();
  for (const [tw, x, y, mu, count] of writes) {
    if (tw > t) break;
    cells.set(`${x},${y}`, [x, y, mu, count, tw]);
  }
  for (const [key, cell] of cells) {
    if (t - cell[4] > maxAge) cells.delete(key);
    else cell.pop();
  }
  return cells;
}
