// The 3D scene: the ground (its profile's pieces, the friction patches
// coloured by mu), the controller's friction map over it, and the robot (trunk, legs, feet, force arrows and
// friction cones), posed from one frame of the run's data.
import * as THREE from 'three';

export const COLORS = {
  footSlip: 0xff2a1a,
  footContact: 0x3a3f47,
  footAir: 0x9aa3ad,
  slipFlag: 0xffa51f,
  trueForce: 0xffd23f,
  qpForce: 0x38d6ff,
  qpCone: 0x38d6ff,
  trueCone: 0xb6ff5c,
  trunk: 0x7d8691,
  trunkFrozen: 0x3b82f6,
  leg: 0xc9ced6,
};

const FORCE_SCALE = 1 / 500; // [m/N] of an arrow
const CONE_HEIGHT = 0.22; // [m]
const UP = new THREE.Vector3(0, 1, 0);

// Ground colour for a friction coefficient: ice blue at 0, earth at 1+.
export function muColor(mu) {
  const stops = [
    [0.0, new THREE.Color(0xcfefff)],
    [0.3, new THREE.Color(0x8fb8d8)],
    [0.7, new THREE.Color(0x8c8272)],
    [1.0, new THREE.Color(0x6b5a46)],
  ];
  const m = Math.min(Math.max(mu, 0), 1);
  for (let i = 1; i < stops.length; i++) {
    if (m <= stops[i][0]) {
      const [m0, c0] = stops[i - 1];
      const [m1, c1] = stops[i];
      return c0.clone().lerp(c1, (m - m0) / (m1 - m0));
    }
  }
  return stops[stops.length - 1][1].clone();
}

// Ground height at x from the profile's pieces [x0, x1, z0, z1].
function heightAt(pieces, x) {
  for (const [x0, x1, z0, z1] of pieces) {
    if (x >= x0 && x <= x1) return x1 > x0 ? z0 + ((x - x0) / (x1 - x0)) * (z1 - z0) : z0;
  }
  if (!pieces.length) return 0;
  return x < pieces[0][0] ? pieces[0][2] : pieces[pieces.length - 1][3];
}

// A strip of the surface from x0 to x1 (split where the profile bends),
// y0 to y1, lifted by `lift` along z.
function surfaceStrip(pieces, x0, x1, y0, y1, lift) {
  const xs = [x0];
  for (const p of pieces) if (p[0] > x0 && p[0] < x1) xs.push(p[0]);
  xs.push(x1);
  const pos = [];
  for (let i = 0; i + 1 < xs.length; i++) {
    const a = xs[i];
    const b = xs[i + 1];
    const za = heightAt(pieces, a) + lift;
    const zb = heightAt(pieces, b) + lift;
    pos.push(a, y0, za, b, y0, zb, b, y1, zb, a, y0, za, b, y1, zb, a, y1, za);
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(pos, 3));
  g.computeVertexNormals();
  return g;
}

function label(text, width) {
  const canvas = document.createElement('canvas');
  canvas.width = 256;
  canvas.height = 64;
  const ctx = canvas.getContext('2d');
  ctx.fillStyle = 'rgba(0,0,0,0)';
  ctx.fillRect(0, 0, 256, 64);
  ctx.font = 'bold 40px sans-serif';
  ctx.fillStyle = '#16324a';
  ctx.textAlign = 'center';
  ctx.textBaseline = 'middle';
  ctx.fillText(text, 128, 34);
  const texture = new THREE.CanvasTexture(canvas);
  const mat = new THREE.MeshBasicMaterial({ map: texture, transparent: true, depthWrite: false });
  return new THREE.Mesh(new THREE.PlaneGeometry(width, width / 4), mat);
}

export function buildGround(ground) {
  const group = new THREE.Group();
  const [bx0, bx1, by0, by1] = ground.box;
  const base = new THREE.Mesh(
    surfaceStrip(ground.pieces, bx0, bx1, by0, by1, 0),
    new THREE.MeshStandardMaterial({ color: muColor(ground.mu), roughness: 0.95, side: THREE.DoubleSide }),
  );
  group.add(base);
  // Later patches win where they overlap: drawn later, on top.
  ground.patches.forEach(([x0, x1, y0, y1, mu], i) => {
    const mat = new THREE.MeshStandardMaterial({
      color: muColor(mu),
      roughness: 0.35,
      metalness: 0.05,
      side: THREE.DoubleSide,
      polygonOffset: true,
      polygonOffsetFactor: -1,
      polygonOffsetUnits: -4 - i,
    });
    const mesh = new THREE.Mesh(surfaceStrip(ground.pieces, x0, x1, y0, y1, 0.001), mat);
    mesh.renderOrder = 1 + i;
    group.add(mesh);
    const w = Math.min(0.6, (x1 - x0) * 0.8);
    const tag = label(`mu ${mu}`, w);
    const cx = 0.5 * (x0 + x1);
    // Beside the robot's path (the box's middle), on the patch.
    const cy = Math.min(Math.max(0.5 * (by0 + by1) + 0.75, y0 + w / 8), y1 - w / 8);
    tag.position.set(cx, cy, heightAt(ground.pieces, cx) + 0.004);
    tag.rotation.z = Math.PI; // read from the robot's left, where the camera starts
    tag.renderOrder = 1000;
    group.add(tag);
  });
  // Lines across the path every 0.5 m, on the surface: they show motion.
  const pts = [];
  for (let x = Math.ceil(bx0 * 2) / 2; x <= bx1; x += 0.5) {
    const z = heightAt(ground.pieces, x) + 0.003;
    pts.push(x, by0, z, x, by1, z);
  }
  const lines = new THREE.BufferGeometry();
  lines.setAttribute('position', new THREE.Float32BufferAttribute(pts, 3));
  group.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color: 0x2d3238, transparent: true, opacity: 0.35 })));
  return group;
}

// The controller's friction map: a tile over each cell it wrote, tinted by
// the cell's estimate (the ground's palette), outlined, and labelled with
// it; shown from the cell's first write on, with its latest write, until
// the map's max_age after it.
export class FrictionMapLayer {
  constructor(ground, map) {
    this.group = new THREE.Group();
    this.tiles = new Map();
    if (!map) return;
    const h = map.cell / 2;
    const z = (x) => heightAt(ground.pieces, x);
    for (const [, x, y] of map.writes) {
      const key = `${x},${y}`;
      if (this.tiles.has(key)) continue;
      const mat = new THREE.MeshStandardMaterial({
        color: 0xffffff,
        roughness: 0.5,
        side: THREE.DoubleSide,
        polygonOffset: true,
        polygonOffsetFactor: -1,
        polygonOffsetUnits: -16,
      });
      const mesh = new THREE.Mesh(surfaceStrip(ground.pieces, x - h, x + h, y - h, y + h, 0.003), mat);
      mesh.renderOrder = 500;
      const corners = [[x - h, y - h], [x + h, y - h], [x + h, y + h], [x - h, y + h]];
      const line = new THREE.LineLoop(
        new THREE.BufferGeometry().setFromPoints(corners.map(([a, b]) => new THREE.Vector3(a, b, z(a) + 0.01))),
        new THREE.LineBasicMaterial({ color: 0x101418 }),
      );
      line.renderOrder = 501;
      const tile = { mesh, mat, line, tag: null, text: '', x, y, width: 3.6 * h };
      this.group.add(mesh, line);
      this.tiles.set(key, tile);
    }
    this.z = z;
  }

  // Shows the map as it was at time t (cells: mapAt's) or hides it;
  // returns the cells shown.
  update(cells, show) {
    const shown = [];
    for (const [key, tile] of this.tiles) {
      const cell = show ? cells.get(key) : undefined;
      tile.mesh.visible = tile.line.visible = !!cell;
      if (tile.tag) tile.tag.visible = !!cell;
      if (!cell) continue;
      const [x, y, mu, count] = cell;
      tile.mat.color.copy(muColor(mu));
      const text = mu.toFixed(3);
      if (text !== tile.text) {
        if (tile.tag) {
          this.group.remove(tile.tag);
          tile.tag.geometry.dispose();
          tile.tag.material.map.dispose();
          tile.tag.material.dispose();
        }
        tile.tag = label(text, tile.width);
        // In front of its tile (which is in front of the patches).
        Object.assign(tile.tag.material, { polygonOffset: true, polygonOffsetFactor: -1, polygonOffsetUnits: -32 });
        tile.tag.position.set(x, y, this.z(x) + 0.007);
        tile.tag.rotation.z = Math.PI;
        tile.tag.renderOrder = 1001;
        this.group.add(tile.tag);
        tile.text = text;
      }
      shown.push({ x, y, z: this.z(x), mu, count });
    }
    return shown;
  }
}

// A cylinder of unit length along y, placed from a to b.
function setSegment(mesh, a, b) {
  const d = new THREE.Vector3().subVectors(b, a);
  const len = d.length();
  mesh.position.copy(a).addScaledVector(d, 0.5);
  mesh.scale.set(1, Math.max(len, 1e-6), 1);
  if (len > 1e-9) mesh.quaternion.setFromUnitVectors(UP, d.divideScalar(len));
}

function setCone(mesh, apex, normal, mu) {
  mesh.position.copy(apex);
  mesh.quaternion.setFromUnitVectors(UP, normal);
  const r = Math.max(mu, 0.001);
  mesh.scale.set(r, 1, r);
}

function setArrow(arrow, from, force) {
  const len = force.length() * FORCE_SCALE;
  if (len < 0.01) {
    arrow.visible = false;
    return;
  }
  arrow.visible = true;
  arrow.position.copy(from);
  arrow.setDirection(force.clone().normalize());
  arrow.setLength(len, Math.min(0.08, 0.35 * len), Math.min(0.04, 0.2 * len));
}

export class Robot {
  constructor(data) {
    this.group = new THREE.Group();
    const [sx, sy, sz] = data.trunk_size;
    this.trunkMat = new THREE.MeshStandardMaterial({ color: COLORS.trunk, roughness: 0.6 });
    this.trunk = new THREE.Mesh(new THREE.BoxGeometry(sx, sy, sz), this.trunkMat);
    this.group.add(this.trunk);
    this.footRadius = data.foot_radius;
    const legMat = new THREE.MeshStandardMaterial({ color: COLORS.leg, roughness: 0.5, metalness: 0.2 });
    const jointMat = new THREE.MeshStandardMaterial({ color: 0x50565f, roughness: 0.5 });
    const radii = [0.03, 0.025, 0.018];
    const coneGeo = new THREE.ConeGeometry(CONE_HEIGHT, CONE_HEIGHT, 32, 1, true);
    coneGeo.rotateX(Math.PI); // apex down
    coneGeo.translate(0, CONE_HEIGHT / 2, 0); // apex at the origin, opening along +y
    this.legs = [0, 1, 2, 3].map(() => {
      const links = radii.map((r) => {
        const m = new THREE.Mesh(new THREE.CylinderGeometry(r, r, 1, 12), legMat);
        this.group.add(m);
        return m;
      });
      const joints = [0, 1, 2].map(() => {
        const j = new THREE.Mesh(new THREE.SphereGeometry(0.035, 16, 12), jointMat);
        this.group.add(j);
        return j;
      });
      // Drawn 1.6 times the foot's radius, to be seen.
      const footMat = new THREE.MeshStandardMaterial({ color: COLORS.footAir, roughness: 0.4 });
      const foot = new THREE.Mesh(new THREE.SphereGeometry(1.6 * data.foot_radius, 20, 14), footMat);
      this.group.add(foot);
      const ring = new THREE.Mesh(
        new THREE.TorusGeometry(0.065, 0.012, 10, 32),
        new THREE.MeshBasicMaterial({ color: COLORS.slipFlag }),
      );
      this.group.add(ring);
      const trueArrow = new THREE.ArrowHelper(UP, new THREE.Vector3(), 0.1, COLORS.trueForce);
      const qpArrow = new THREE.ArrowHelper(UP, new THREE.Vector3(), 0.1, COLORS.qpForce);
      for (const a of [trueArrow, qpArrow]) {
        a.line.material.linewidth = 2;
        this.group.add(a);
      }
      const qpCone = new THREE.Mesh(
        coneGeo,
        new THREE.MeshBasicMaterial({ color: COLORS.qpCone, transparent: true, opacity: 0.16, depthWrite: false, side: THREE.DoubleSide }),
      );
      const trueCone = new THREE.Mesh(
        coneGeo,
        new THREE.MeshBasicMaterial({ color: COLORS.trueCone, wireframe: true, transparent: true, opacity: 0.45, depthWrite: false }),
      );
      this.group.add(qpCone, trueCone);
      return { links, joints, foot, footMat, ring, trueArrow, qpArrow, qpCone, trueCone };
    });
  }

  // Poses everything from frames a and b (positions alpha of the way to b);
  // flags and forces are a's. Returns each foot's shown state.
  update(a, b, alpha) {
    const lerp = (i) => a.p[i] + alpha * (b.p[i] - a.p[i]);
    const point = (leg, k) => {
      const o = 12 * leg + 3 * k;
      return new THREE.Vector3(lerp(o), lerp(o + 1), lerp(o + 2));
    };
    const pos = new THREE.Vector3(...a.b.slice(0, 3)).lerp(new THREE.Vector3(...b.b.slice(0, 3)), alpha);
    const qa = new THREE.Quaternion(a.b[4], a.b[5], a.b[6], a.b[3]).normalize();
    const qb = new THREE.Quaternion(b.b[4], b.b[5], b.b[6], b.b[3]).normalize();
    this.trunk.position.copy(pos);
    this.trunk.quaternion.copy(qa.slerp(qb, alpha));
    this.trunkMat.color.setHex(a.fz ? COLORS.trunkFrozen : COLORS.trunk);
    const shown = [];
    this.legs.forEach((L, leg) => {
      const p = [0, 1, 2, 3].map((k) => point(leg, k));
      for (let k = 0; k < 3; k++) setSegment(L.links[k], p[k], p[k + 1]);
      for (let k = 0; k < 3; k++) L.joints[k].position.copy(p[k]);
      const foot = p[3];
      L.foot.position.copy(foot);
      const contact = (a.c >> leg) & 1;
      const stance = (a.s >> leg) & 1;
      const slipFlag = (a.sf >> leg) & 1;
      const trueSlip = (a.ts >> leg) & 1;
      const color = trueSlip ? COLORS.footSlip : contact ? COLORS.footContact : COLORS.footAir;
      L.footMat.color.setHex(color);
      L.footMat.emissive.setHex(trueSlip ? COLORS.footSlip : 0x000000);
      L.footMat.emissiveIntensity = trueSlip ? 0.7 : 0;
      L.ring.visible = !!slipFlag;
      const qpNormal = new THREE.Vector3(...a.n.slice(3 * leg, 3 * leg + 3));
      const trueNormal = new THREE.Vector3(...a.tn.slice(3 * leg, 3 * leg + 3));
      if (qpNormal.lengthSq() < 1e-6) qpNormal.set(0, 0, 1);
      if (trueNormal.lengthSq() < 1e-6) trueNormal.set(0, 0, 1);
      qpNormal.normalize();
      trueNormal.normalize();
      const apex = foot.clone().addScaledVector(trueNormal, -this.footRadius);
      L.ring.position.copy(foot);
      L.ring.quaternion.setFromUnitVectors(new THREE.Vector3(0, 0, 1), trueNormal);
      L.trueCone.visible = !!contact;
      L.qpCone.visible = !!stance;
      setCone(L.qpCone, apex, qpNormal, a.mu[leg]);
      setCone(L.trueCone, apex, trueNormal, a.tmu[leg]);
      const f = new THREE.Vector3(...a.f.slice(3 * leg, 3 * leg + 3));
      const g = new THREE.Vector3(...a.g.slice(3 * leg, 3 * leg + 3));
      setArrow(L.trueArrow, apex, f);
      if (!contact) L.trueArrow.visible = false;
      setArrow(L.qpArrow, apex, g);
      if (!stance) L.qpArrow.visible = false;
      shown.push({
        leg,
        contact: !!contact,
        stance: !!stance,
        slipFlag: !!slipFlag,
        trueSlip: !!trueSlip,
        color: '#' + L.footMat.color.getHexString(),
        ring: L.ring.visible,
        position: foot.toArray(),
        muUsed: a.mu[leg],
        muTrue: a.tmu[leg],
      });
    });
    return { base: pos, shown };
  }
}
