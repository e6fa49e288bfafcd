// The replay page: reads the run's data from the page, builds the scene,
// and plays it on a timeline (play/pause, speed, scrubbing, previous/next
// true slip, the ground as the friction map has it or as it is). The camera follows the trunk; drag to orbit, wheel to zoom.
//
// For tests, window.hyqReplay is read-only: `state` (a fresh snapshot: the
// time, the frames rendered so far, each foot's shown state and where it is
// on the canvas, the friction map's cells shown) and nothing that changes the replay; the page is driven
// through its controls.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { sampleAt, nextSlip, previousSlip, mapAt } from './data.js';
import { Robot, buildGround, FrictionMapLayer } from './scene.js';

const data = JSON.parse(document.getElementById('replay-data').textContent);
const frames = data.frames;
const slips = data.slips.slice().sort((p, q) => p[0] - q[0]);
const t0 = frames.length ? frames[0].t : 0;
const t1 = frames.length ? frames[frames.length - 1].t : 0;
const $ = (id) => document.getElementById(id);

// --- scene
const view = $('view');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
view.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0x1d2127);
scene.add(new THREE.HemisphereLight(0xdfe8f5, 0x3a3228, 1.4));
const sun = new THREE.DirectionalLight(0xffffff, 1.8);
sun.position.set(-3, 4, 8);
scene.add(sun);
scene.add(buildGround(data.ground));
// The friction map's tiles over the ground, when the run kept a map.
const frictionMap = new FrictionMapLayer(data.ground, data.map);
scene.add(frictionMap.group);
const robot = new Robot(data);
scene.add(robot.group);

const camera = new THREE.PerspectiveCamera(45, 1, 0.02, 200);
camera.up.set(0, 0, 1);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;
// From the left side, a little behind and above the trunk.
const start = frames.length ? new THREE.Vector3(...frames[0].b.slice(0, 3)) : new THREE.Vector3();
camera.position.copy(start).add(new THREE.Vector3(-0.9, 2.3, 1.0));
controls.target.copy(start);
controls.update();

function resize() {
  const w = view.clientWidth || 1;
  const h = view.clientHeight || 1;
  renderer.setSize(w, h);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);
resize();

// --- header
const legs = data.legs;
$('title').textContent = `HyQ replay: ${data.scenario}`;
$('subtitle').textContent =
  `seed ${data.seed}, slip recovery ${data.recovery ? 'on' : 'off'}, ${data.controller} on ${data.engine}; ` +
  `${slips.length} true slips (contact point faster than ${data.true_slip_speed} m/s), ` +
  `${data.slip_flags.length} slip flags, ${data.freezes.length} freezes`;
const rows = legs.map((name) => {
  const tr = document.createElement('tr');
  tr.innerHTML = `<th>${name}</th>` + '<td></td>'.repeat(6);
  document.querySelector('#legs tbody').appendChild(tr);
  return [...tr.querySelectorAll('td')];
});

// --- timeline
const scrub = $('scrub');
scrub.min = String(t0);
scrub.max = String(t1);
let time = t0;
let playing = false;
let speed = 1;
let rendered = 0;
let shown = null;

const marks = $('marks');
function drawMarks() {
  const w = marks.clientWidth;
  const h = marks.clientHeight;
  marks.width = w;
  marks.height = h;
  const ctx = marks.getContext('2d');
  ctx.fillStyle = '#1b1f25';
  ctx.fillRect(0, 0, w, h);
  const x = (t) => (t1 > t0 ? ((t - t0) / (t1 - t0)) * (w - 1) : 0);
  const rowH = h / 4;
  const span = (a, b, y, hh, color) => {
    ctx.fillStyle = color;
    ctx.fillRect(x(a), y, Math.max(2, x(b) - x(a)), hh);
  };
  for (const [a, b] of data.freezes) span(a, b, 0, h, 'rgba(59,130,246,0.45)');
  for (const [a, b, leg] of data.slip_flags) span(a, b, leg * rowH + rowH * 0.5, rowH * 0.45, '#ffa51f');
  for (const [a, b, leg] of slips) span(a, b, leg * rowH + 1, rowH * 0.45, '#ff2a1a');
}
window.addEventListener('resize', drawMarks);
drawMarks();
marks.addEventListener('click', (e) => {
  const r = marks.getBoundingClientRect();
  seek(t0 + ((e.clientX - r.left) / r.width) * (t1 - t0));
});

function seek(t) {
  time = Math.min(Math.max(t, t0), t1);
}
function setPlaying(p) {
  playing = p;
  $('play').textContent = p ? 'pause' : 'play';
}
function jumpToSlip(s) {
  if (!s) return;
  setPlaying(false);
  seek(s[0]);
}

$('play').addEventListener('click', () => {
  if (!playing && time >= t1) seek(t0);
  setPlaying(!playing);
});
$('speed').addEventListener('change', (e) => {
  speed = Number(e.target.value);
});
scrub.addEventListener('input', () => seek(Number(scrub.value)));
// The ground as the controller's map has it (tiles over its cells) or
// as it is (the tiles hidden): the 'map' button or m.
let showMap = !!data.map;
$('map').style.display = data.map ? '' : 'none';
$('map-legend').style.display = data.map ? '' : 'none';
function setShowMap(on) {
  showMap = on;
  $('map').textContent = on ? 'ground: map' : 'ground: truth';
}
setShowMap(showMap);
$('map').addEventListener('click', () => setShowMap(!showMap && !!data.map));
$('next-slip').addEventListener('click', () => jumpToSlip(nextSlip(slips, time)));
$('prev-slip').addEventListener('click', () => jumpToSlip(previousSlip(slips, time)));
window.addEventListener('keydown', (e) => {
  if (e.target && e.target.tagName === 'SELECT') return;
  if (e.key === ' ') {
    e.preventDefault();
    $('play').click();
  } else if (e.key === 'n') $('next-slip').click();
  else if (e.key === 'p') $('prev-slip').click();
  else if (e.key === 'm') $('map').click();
});

// --- drawing
function slipText() {
  const current = slips.filter((s) => s[0] <= time + 0.0005 && time < s[1]);
  const at = current.length ? current : slips.filter((s) => Math.abs(s[0] - time) < 0.0005);
  if (!at.length) return '';
  return at
    .map((s) => `true slip ${slips.indexOf(s) + 1}/${slips.length}: ${legs[s[2]]} ` +
      `${s[0].toFixed(3)}-${s[1].toFixed(3)} s (${Math.round((s[1] - s[0]) * 1000)} ms)`)
    .join('; ');
}

function draw() {
  if (!frames.length) return;
  const { index, frame, next, alpha } = sampleAt(frames, time);
  const before = robot.trunk.position.clone();
  const { base, shown: feet } = robot.update(frame, next, alpha);
  const mapCells = frictionMap.update(data.map ? mapAt(data.map.writes, time, data.map.max_age) : new Map(), showMap);
  // Follow the trunk: move camera and target together.
  const delta = base.clone().sub(rendered ? before : controls.target);
  camera.position.add(delta);
  controls.target.add(delta);
  controls.update();
  renderer.render(scene, camera);
  rendered += 1;

  const w = renderer.domElement.clientWidth;
  const h = renderer.domElement.clientHeight;
  for (const c of mapCells) {
    const p = new THREE.Vector3(c.x, c.y, c.z).project(camera);
    c.screen = p.z < 1 ? [((p.x + 1) / 2) * w, ((1 - p.y) / 2) * h] : null;  // null: behind the camera
  }
  for (const f of feet) {
    const p = new THREE.Vector3(...f.position).project(camera);
    f.screen = [((p.x + 1) / 2) * w, ((1 - p.y) / 2) * h];
    const cells = rows[f.leg];
    const yes = (v, cls) => (v ? `<span class="${cls}">yes</span>` : '-');
    cells[0].innerHTML = yes(f.contact, 'on');
    cells[1].innerHTML = yes(f.stance, 'on');
    cells[2].innerHTML = yes(f.slipFlag, 'flag');
    cells[3].innerHTML = yes(f.trueSlip, 'slip');
    cells[4].textContent = f.stance ? f.muUsed.toFixed(2) : '-';
    cells[5].textContent = f.contact ? f.muTrue.toFixed(2) : '-';
  }
  $('freeze').style.display = frame.fz ? 'block' : 'none';
  $('time').textContent = `t ${time.toFixed(3)} / ${t1.toFixed(1)} s`;
  $('slip-info').textContent = slipText();
  if (document.activeElement !== scrub) scrub.value = String(time);
  shown = { time, frameIndex: index, frameTime: frame.t, freeze: !!frame.fz, feet, showMap, mapCells };
}

let last = performance.now();
function loop(now) {
  const dt = Math.min((now - last) / 1000, 0.1);
  last = now;
  if (playing) {
    seek(time + dt * speed);
    if (time >= t1) setPlaying(false);
  }
  draw();
  requestAnimationFrame(loop);
}
requestAnimationFrame(loop);

const deepFreeze = (o) => {
  if (o && typeof o === 'object') {
    Object.values(o).forEach(deepFreeze);
    Object.freeze(o);
  }
  return o;
};
window.hyqReplay = Object.freeze({
  get state() {
    return deepFreeze(JSON.parse(JSON.stringify({
      renderedFrames: rendered,
      playing,
      speed,
      slips,
      ...(shown || { time, feet: [] }),
    })));
  },
});
