// The replay page in headless Chromium (Debian's /usr/bin/chromium, driven
// by playwright-core): a short hyq_sim run with a true slip, its
// replay.html opened from disk with no network, then checked through the
// page's own controls. Exit 0 when every check passes.
//
//   node tests/browser/replay_test.mjs [--build build/host] [--screenshot FILE]
//        [--scenario FILE --duration S] [--recovery on|off] [--slip N] [--map]
//
// --build: the host build folder (hyq_sim, web/replay_template.html, and
// browser-test/node_modules with playwright-core: `make browser-test-deps`).
// --screenshot: where the picture at the slip goes (default
// <build>/browser-test/replay_slip.png). The run: stance_slip.yaml over 2 s
// unless --scenario and --duration say otherwise; the checks are made at
// its N-th true slip (default the first). --map: the run keeps a friction
// map; its tiles are checked against friction_map.json, and the
// screenshot is taken at the end with the map shown.
import { mkdtempSync, readFileSync, rmSync, mkdirSync, existsSync } from 'node:fs';
import { createRequire } from 'node:module';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath, pathToFileURL } from 'node:url';

const started = Date.now();
const repo = resolve(dirname(fileURLToPath(import.meta.url)), '../..');
const args = process.argv.slice(2);
const option = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 && i + 1 < args.length ? args[i + 1] : fallback;
};
const build = resolve(repo, option('--build', 'build/host'));
const screenshot = resolve(option('--screenshot', join(build, 'browser-test', 'replay_slip.png')));
const CHROMIUM = '/usr/bin/chromium';
// Software WebGL: a container has no GPU.
const CHROMIUM_ARGS = ['--no-sandbox', '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist'];
// stance_slip over 2 s: LF slips on its low-friction spot at about 1.3 s.
const SCENARIO = option('--scenario', 'sim_host/scenarios/stance_slip.yaml');
const DURATION = option('--duration', '2');
const RECOVERY = option('--recovery', null);
const SLIP = Number(option('--slip', '1'));
const MAP = args.includes('--map');

// The friction map's tiles: none before the first write, the first write's
// cell right after it, at the end every cell of friction_map.json not yet
// forgotten (max_age) with its estimate, and the m key hides them (the
// label on a tile goes).
async function checkMap(page, state, settled, pixels) {
  const map = JSON.parse(readFileSync(join(out, 'friction_map.json'), 'utf8'));
  const { writes, max_age: maxAge } = await page.evaluate(() => JSON.parse(document.getElementById('replay-data').textContent).map);
  if (!writes.length) return check(false, 'the run wrote into its friction map');
  const [tw, xw, yw, muw] = writes[0];
  await page.locator('#scrub').fill(String(Math.round((tw - 0.01) * 1000) / 1000));
  let s = await settled();
  check(s.showMap && s.mapCells.length === 0, 'no map tile before the first write', `${s.mapCells.length} tiles at ${s.time}`);
  await page.locator('#scrub').fill(String(Math.round(tw * 1000) / 1000));
  s = await settled();
  const first = s.mapCells.find((c) => Math.abs(c.x - xw) < 1e-9 && Math.abs(c.y - yw) < 1e-9);
  check(first && Math.abs(first.mu - muw) < 1e-9, "the first write's tile shows its estimate",
    JSON.stringify(first));
  await page.locator('#scrub').fill(await page.locator('#scrub').getAttribute('max'));
  s = await settled();
  // The cells not yet forgotten (written within max_age of the end).
  const live = map.cells.filter((c) => s.time - c.time <= maxAge);
  const wrong = live.filter((c) => !s.mapCells.some((t) => Math.abs(t.x - c.x) < 1e-3 &&
    Math.abs(t.y - c.y) < 1e-3 && Math.abs(t.mu - c.mu) < 1e-4 && t.count === c.count));
  check(live.length > 0 && s.mapCells.length === live.length && wrong.length === 0,
    "at the end, every cell of friction_map.json written within max_age, with its estimate",
    `${s.mapCells.length} tiles, ${live.length} of ${map.cells.length} cells, ${wrong.length} not matched`);
  await page.screenshot({ path: screenshot });
  // The tile nearest the view's middle.
  const off = (c) => Math.hypot(c.screen[0] - 640, c.screen[1] - 357);
  const tile = s.mapCells.filter((c) => c.screen && c.screen[0] > 40 && c.screen[0] < 1240 && c.screen[1] > 40 &&
    c.screen[1] < 670).sort((a, b) => off(a) - off(b))[0];
  if (!tile) return check(false, 'a map tile in view at the end');
  // The tile's label and outline (dark on it) are there with the map and
  // gone without: pixels around its centre that turn much lighter.
  const shownPx = await pixels(tile.screen, 12);
  await page.keyboard.press('m');
  s = await settled();
  const hiddenPx = await pixels(tile.screen, 12);
  const lighter = hiddenPx.sums.filter((v, i) => v - shownPx.sums[i] > 90).length;
  check(!s.showMap && s.mapCells.length === 0 && lighter >= 20,
    'm hides the tiles: the label on one goes', `${lighter} of ${hiddenPx.sums.length} pixels turn lighter`);
  await page.keyboard.press('m');
  s = await settled();
  check(s.showMap && s.mapCells.length === live.length, 'm shows them again');
}

let passed = 0;
let failed = 0;
function check(ok, what, detail = '') {
  if (ok) passed++;
  else failed++;
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}${detail ? ': ' + detail : ''}`);
}
function fatal(message) {
  console.log(`replay_test: ${message}`);
  console.log(`${passed} passed, ${failed + 1} failed`);
  process.exit(1);
}

const modules = join(build, 'browser-test', 'node_modules');
if (!existsSync(join(modules, 'playwright-core'))) fatal(`no playwright-core in ${modules} (make browser-test-deps)`);
if (!existsSync(CHROMIUM)) fatal(`no ${CHROMIUM} (apt-get install chromium; make test installs it)`);
const { chromium } = createRequire(join(modules, 'x.js'))('playwright-core');

// A short run of its own, with a true slip in it.
const out = mkdtempSync(join(tmpdir(), 'hyq_replay_test_'));
let browser;
try {
  try {
    execFileSync(join(build, 'hyq_sim'),
      ['run', resolve(repo, SCENARIO), '--duration', DURATION, '--replay', '--no-log', '--out', out,
        ...(RECOVERY ? ['--recovery', RECOVERY] : [])],
      { stdio: ['ignore', 'ignore', 'pipe'] });
  } catch (e) {
    fatal(`hyq_sim failed: ${String(e.stderr || e.message).trim()}`);
  }
  const events = readFileSync(join(out, 'events.csv'), 'utf8').trim().split('\n').slice(1).map((l) => l.split(','));
  const legs = ['LF', 'RF', 'LH', 'RH'];
  const slip = events.filter((e) => e[2] === 'slip_start')[SLIP - 1];
  if (!slip) fatal(`${SCENARIO} over ${DURATION} s has no slip_start number ${SLIP} in events.csv`);
  const slipTime = Number(slip[0]);
  const slipLeg = legs.indexOf(slip[3]);
  const flag = events.find((e) => e[2] === 'slip_flag_on' && e[3] === slip[3] && Number(e[0]) >= slipTime);

  browser = await chromium.launch({ executablePath: CHROMIUM, headless: true, args: CHROMIUM_ARGS });
  const page = await browser.newPage({ viewport: { width: 1280, height: 800 } });
  const errors = [];
  const requests = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(String(e)));
  page.on('request', (r) => { if (!r.url().startsWith('file:') && !r.url().startsWith('data:')) requests.push(r.url()); });
  await page.goto(pathToFileURL(join(out, 'replay.html')).href);

  const state = () => page.evaluate(() => window.hyqReplay.state);
  const rendered = async (n) => page.waitForFunction((k) => window.hyqReplay && window.hyqReplay.state.renderedFrames >= k, n, { timeout: 20000 });
  // After an action on the page: two more frames drawn, then its state.
  const settled = async () => {
    await rendered((await state()).renderedFrames + 2);
    return state();
  };
  // Pixels of the 3D view in a square of half-side r around (x, y) [CSS px]:
  // how many are the slipping foot's red, and how many distinct colours.
  const pixels = (at, r) => page.evaluate(({ at, r }) => {
    const src = document.querySelector('#view canvas');
    const c = document.createElement('canvas');
    c.width = src.width;
    c.height = src.height;
    const ctx = c.getContext('2d');
    ctx.drawImage(src, 0, 0);
    const s = src.width / src.clientWidth;
    const x0 = Math.max(0, Math.round((at[0] - r) * s));
    const y0 = Math.max(0, Math.round((at[1] - r) * s));
    const w = Math.min(c.width - x0, Math.round(2 * r * s));
    const h = Math.min(c.height - y0, Math.round(2 * r * s));
    const d = ctx.getImageData(x0, y0, w, h).data;
    let red = 0;
    const sums = [];
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4) {
      if (d[i] > 170 && d[i + 1] < 100 && d[i + 2] < 90) red++;
      sums.push(d[i] + d[i + 1] + d[i + 2]);
      colours.add((d[i] >> 3) * 1024 + (d[i + 1] >> 3) * 32 + (d[i + 2] >> 3));
    }
    return { red, sums, colours: colours.size, total: d.length / 4 };
  }, { at, r });

  await rendered(5);
  let s = await state();
  check(s.renderedFrames >= 5, 'the page renders frames', `${s.renderedFrames} so far`);
  const whole = await pixels([640, 357], 640);
  check(whole.colours > 50, 'the 3D view is not blank', `${whole.colours} distinct colours`);
  const foot0 = s.feet[slipLeg];
  check(!foot0.trueSlip, `${slip[3]} is not slipping at the start`);
  const red0 = await pixels(foot0.screen, 14);
  check(red0.red === 0, `no slip red around ${slip[3]}'s foot at the start`, `${red0.red} red pixels`);

  // Scrubbing: the slider moves the replay.
  await page.locator('#scrub').fill('0.5');
  s = await settled();
  check(Math.abs(s.time - 0.5) < 1e-6, 'scrubbing to 0.5 s', `time ${s.time}`);

  // Play moves time forward; pause stops it.
  await page.click('#play');
  await page.waitForTimeout(400);
  await page.click('#play');
  s = await settled();
  check(s.time > 0.55 && !s.playing, 'play advances time and pause stops it', `time ${s.time}`);

  // Jump to the next true slip (from the start for the N-th): its foot
  // shown slipping.
  // Slips that start in the same tick are one jump: one press per distinct
  // start time up to the N-th slip's.
  const starts = new Set(events.filter((e) => e[2] === 'slip_start').slice(0, SLIP).map((e) => e[1]));
  await page.locator('#scrub').fill(await page.locator('#scrub').getAttribute('min'));
  for (let i = 0; i < starts.size; i++) await page.click('#next-slip');
  s = await settled();
  check(Math.abs(s.time - slipTime) < 1e-6 && Math.abs(s.frameTime - slipTime) < 1e-6,
    'next slip jumps to the slip of events.csv', `time ${s.time}, frame ${s.frameTime}, events.csv ${slipTime}`);
  const foot = s.feet[slipLeg];
  check(foot.trueSlip && foot.color === '#ff2a1a', `${slip[3]} is shown slipping`, `trueSlip ${foot.trueSlip}, colour ${foot.color}`);
  // The other feet as events.csv has them at that time.
  const slippingAt = (leg, t) => {
    let on = false;
    for (const e of events) {
      if (Number(e[0]) > t) break;
      if (e[3] === legs[leg] && (e[2] === 'slip_start' || e[2] === 'slip_end')) on = e[2] === 'slip_start';
    }
    return on;
  };
  const wrong = s.feet.filter((f) => f.trueSlip !== slippingAt(f.leg, slipTime)).map((f) => legs[f.leg]);
  check(wrong.length === 0, 'every foot shown slipping or not as events.csv has it', wrong.join(' '));
  const red = await pixels(foot.screen, 14);
  check(red.red >= 20, `the canvas shows ${slip[3]}'s foot red`, `${red.red} red pixels of ${red.total}`);
  const info = await page.locator('#slip-info').textContent();
  check(info.includes(slip[3]), 'the slip is named under the timeline', JSON.stringify(info));
  mkdirSync(dirname(screenshot), { recursive: true });
  if (!MAP) await page.screenshot({ path: screenshot });

  // The controller's slip flag, a few ticks later: the ring around the foot.
  if (flag) {
    await page.locator('#scrub').fill(flag[0]);
    s = await settled();
    check(s.feet[slipLeg].slipFlag && s.feet[slipLeg].ring, `${slip[3]}'s slip flag is shown at ${flag[0]} s`);
  } else {
    check(false, `a slip_flag_on for ${slip[3]} in events.csv`);
  }

  if (MAP) await checkMap(page, state, settled, pixels);
  else check(s.showMap === false && s.mapCells.length === 0, 'a run without a map shows none');

  check(errors.length === 0, 'no console errors or page errors', errors.join(' | '));
  check(requests.length === 0, 'no network requests', requests.join(' '));
  console.log(`screenshot: ${screenshot}`);
} catch (e) {
  check(false, 'the checks ran to their end', String(e.message || e).split('\n')[0]);
} finally {
  if (browser) await browser.close();
  rmSync(out, { recursive: true, force: true });
}
console.log(`wall time ${((Date.now() - started) / 1000).toFixed(1)} s`);
console.log(`${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
