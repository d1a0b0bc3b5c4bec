// The page of `softevo view` (docs/viewer.md): draws the frames of a session, either streamed
// by the server over the WebSocket /ws (live simulation, steering, scrubbing) or embedded in an
// --export-html file (replayed here, no network). Everything physical comes from softevo; this
// page only draws and sends the user's commands.
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { StripChart } from 'softevo/plots.js';

THREE.Object3D.DEFAULT_UP.set(0, 0, 1);  // softevo's z is up

const $ = (id) => document.getElementById(id);
// What tests and scripts read: counts and the last frame.
const probe = { frames: 0, renders: 0, fps: 0, bytes: 0, hello: null, ended: null, errors: [],
  saved: null, last: null, mode: '', renderedIndex: -1 };
window.softevo = probe;

// ---------------------------------------------------------------- scene
const sceneEl = $('scene');
const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(window.devicePixelRatio || 1);
sceneEl.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xffffff);
const camera = new THREE.PerspectiveCamera(35, 1, 0.002, 200);
const controls = new OrbitControls(camera, renderer.domElement);
controls.enableDamping = false;
// The scene is drawn only when something in it changed (a frame, the camera, the size, the
// target) or while recording: a paused or finished page costs no CPU or GPU time.
let redraw = true;
const changed = () => { redraw = true; };
controls.addEventListener('change', changed);
scene.add(new THREE.HemisphereLight(0xffffff, 0x8a8a80, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.4);
sun.position.set(-1, -2, 3);
scene.add(sun);

let hello = null;
let surface = null;  // the body's lattice: corners, neighbours, faces (buildSurface)
let voxelMesh = null, chamberMesh = null, channelMesh = null, floorGroup = null, targetLine = null, pathLine = null;
let start = new THREE.Vector3();  // centroid of the first frame [m]
let floorZ = -0.005;
let lastCentroid = null;
let floorCentre = null;  // where the floor, its grid and the scale bar are centred [m]
let pathCount = 0, pathLast = -1;  // centroid path points drawn, last record among them
let charts = null;
let fitnessSeries = [];  // indices of the components drawn in the fitness plot
let lastFrame = null;  // the frame shown
let duration = 10;

function resize() {
  changed();
  const w = sceneEl.clientWidth, h = sceneEl.clientHeight;
  renderer.setSize(w, h, false);
  camera.aspect = w / Math.max(h, 1);
  camera.updateProjectionMatrix();
}
window.addEventListener('resize', resize);

// A text label on the floor (scale bar).
// `size` is the height [m]; the width follows the text, so that none of it is cut off. The mesh's
// left edge is at x = 0 of its position.
function label(text, size) {
  const c = document.createElement('canvas');
  const font = '40px sans-serif';
  const g0 = c.getContext('2d');
  g0.font = font;
  c.width = Math.ceil(g0.measureText(text).width) + 8; c.height = 64;
  const g = c.getContext('2d');
  g.fillStyle = '#333';
  g.font = font;
  g.fillText(text, 4, 46);
  const tex = new THREE.CanvasTexture(c);
  const width = size * c.width / c.height;
  const geo = new THREE.PlaneGeometry(width, size);
  geo.translate(width / 2, 0, 0);
  return new THREE.Mesh(geo, new THREE.MeshBasicMaterial({ map: tex, transparent: true, depthWrite: false }));
}

// The ground (hello.terrain, sampled by softevo from physics/terrain; absent for the flat floor):
// {x0, y0, step, nx, ny, z: base64 float32 surface heights [m], x fastest}.
let terrainZ = null;
function decodeTerrain(t) {
  if (!t) return null;
  const raw = Uint8Array.from(atob(t.z), (c) => c.charCodeAt(0));
  return new Float32Array(raw.buffer, 0, t.nx * t.ny);
}
// Surface height under (x, y) [m]: the flat floor, or the sent grid interpolated between its
// samples (the flat floor outside it).
function groundZ(x, y) {
  const t = hello && hello.terrain;
  if (!t || !terrainZ) return floorZ;
  const u = (x - t.x0) / t.step, v = (y - t.y0) / t.step;
  if (!(u >= 0 && v >= 0 && u <= t.nx - 1 && v <= t.ny - 1)) return floorZ;
  const i = Math.min(Math.floor(u), t.nx - 2), j = Math.min(Math.floor(v), t.ny - 2);
  const a = u - i, b = v - j, z = (ii, jj) => terrainZ[jj * t.nx + ii];
  return (1 - b) * ((1 - a) * z(i, j) + a * z(i + 1, j)) + b * ((1 - a) * z(i, j + 1) + a * z(i + 1, j + 1));
}
// Highest surface along a segment (lines drawn on the ground stay above it).
function groundMax(x0, y0, x1, y1) {
  let z = -Infinity;
  for (let k = 0; k <= 20; k++) z = Math.max(z, groundZ(x0 + (x1 - x0) * k / 20, y0 + (y1 - y0) * k / 20));
  return z;
}

// The terrain as a shaded height mesh: Lambert-lit (its normals from the heights), tinted darker
// in the valleys and lighter on the tops, with the 10-voxel grid as a repeating texture.
function terrainMesh(t, s) {
  const n = t.nx * t.ny;
  const position = new Float32Array(3 * n), colour = new Float32Array(3 * n), uv = new Float32Array(2 * n);
  let lo = Infinity, hi = -Infinity;
  for (const z of terrainZ) { lo = Math.min(lo, z); hi = Math.max(hi, z); }
  const range = Math.max(hi - lo, 1e-6);
  for (let j = 0; j < t.ny; j++) for (let i = 0; i < t.nx; i++) {
    const k = j * t.nx + i, x = t.x0 + i * t.step, y = t.y0 + j * t.step, z = terrainZ[k];
    position.set([x, y, z], 3 * k);
    const g = 0.56 + 0.36 * (z - lo) / range;
    colour.set([g, g, g * 0.97], 3 * k);
    uv.set([x / (10 * s), y / (10 * s)], 2 * k);
  }
  const index = [];
  for (let j = 0; j + 1 < t.ny; j++) for (let i = 0; i + 1 < t.nx; i++) {
    const a = j * t.nx + i, b = a + 1, c = a + t.nx, d = c + 1;
    index.push(a, b, d, a, d, c);
  }
  const geo = new THREE.BufferGeometry();
  geo.setAttribute('position', new THREE.BufferAttribute(position, 3));
  geo.setAttribute('color', new THREE.BufferAttribute(colour, 3));
  geo.setAttribute('uv', new THREE.BufferAttribute(uv, 2));
  geo.setIndex(index);
  geo.computeVertexNormals();
  const c = document.createElement('canvas');
  c.width = c.height = 64;
  const g = c.getContext('2d');
  g.fillStyle = '#ffffff'; g.fillRect(0, 0, 64, 64);
  g.fillStyle = '#c8c8c2'; g.fillRect(0, 0, 64, 2); g.fillRect(0, 0, 2, 64);
  const tex = new THREE.CanvasTexture(c);
  tex.wrapS = tex.wrapT = THREE.RepeatWrapping;
  tex.anisotropy = 4;
  const mesh = new THREE.Mesh(geo, new THREE.MeshLambertMaterial({ vertexColors: true, map: tex }));
  mesh.name = 'terrain';
  return { mesh, lo };
}

function buildFloor(center) {
  if (floorGroup) scene.remove(floorGroup);
  floorCentre = center.clone();
  floorGroup = new THREE.Group();
  const s = hello.voxel_size;
  const extent = 2.0;  // [m] half width
  // With a terrain the flat floor lies under its lowest point (around the sampled square).
  let planeZ = floorZ;
  if (hello.terrain && terrainZ) {
    const { mesh, lo } = terrainMesh(hello.terrain, s);
    floorGroup.add(mesh);
    planeZ = Math.min(floorZ, lo) - 0.001;
  }
  const plane = new THREE.Mesh(new THREE.PlaneGeometry(2 * extent, 2 * extent),
    new THREE.MeshBasicMaterial({ color: 0xd6d6d1 }));
  plane.position.set(center.x, center.y, planeZ - 0.0002);
  plane.name = 'floor';
  floorGroup.add(plane);
  for (const [step, colour] of [[10 * s, 0xbdbdb6], [100 * s, 0x8d8d86]]) {
    const divisions = Math.round(2 * extent / step);
    const grid = new THREE.GridHelper(2 * extent, divisions, colour, colour);
    grid.rotation.x = Math.PI / 2;
    grid.position.set(center.x, center.y, planeZ + (step > 20 * s ? 0.0001 : 0));
    floorGroup.add(grid);
  }
  // Scale bar: 10 cm (10 voxel lengths of 1 cm) in black, with its label.
  const bar = 0.1;
  const y0 = center.y - 0.12;
  const barZ = groundMax(center.x - 0.05, y0 - 0.02, center.x + 0.05, y0 - 0.02) + 0.0003;
  const barGeo = new THREE.BufferGeometry().setFromPoints([
    new THREE.Vector3(center.x - 0.05, y0, barZ), new THREE.Vector3(center.x - 0.05 + bar, y0, barZ)]);
  floorGroup.add(new THREE.Line(barGeo, new THREE.LineBasicMaterial({ color: 0x000000 })));
  const text = label('10 cm (grid 10 / 100 voxels)', 0.012);
  text.position.set(center.x - 0.05, y0 - 0.008, barZ);
  floorGroup.add(text);
  scene.add(floorGroup);
  probe.terrainVertices = hello.terrain && terrainZ ? terrainZ.length : 0;
}

// The server sends the ground under the path so far when the robot nears the edge of the grid
// the page has (a live robot walks off any fixed square).
function groundChanged(t) {
  changed();
  hello.terrain = t;
  terrainZ = decodeTerrain(t);
  probe.terrainUpdates = (probe.terrainUpdates || 0) + 1;
  buildFloor(lastCentroid || start);
  if (targetLine) setTarget(dialDeg);
}

function setTarget(deg) {
  changed();
  if (!hello.directed) return;
  // On a terrain the line follows the ground (a point per 1.5 cm), else 2 points on the floor.
  const points = hello.terrain ? 101 : 2;
  if (!targetLine) {
    const geo = new THREE.BufferGeometry();
    geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * points), 3));
    targetLine = new THREE.Line(geo, new THREE.LineBasicMaterial({ color: 0xdd1414 }));
    targetLine.frustumCulled = false;
    scene.add(targetLine);
  }
  const r = deg * Math.PI / 180, len = 1.5;
  const p = targetLine.geometry.attributes.position;
  for (let k = 0; k < points; k++) {
    const x = start.x + len * Math.cos(r) * k / (points - 1), y = start.y + len * Math.sin(r) * k / (points - 1);
    p.setXYZ(k, x, y, groundZ(x, y) + 0.0006);
  }
  p.needsUpdate = true;
  if (deg !== dialDeg) {
    $('target').textContent = deg.toFixed(0);
    dialDeg = deg;
    drawDial();
  }
}

function setup(h) {
  changed();
  hello = h;
  probe.hello = h;
  duration = (h.planned_records - 1) / h.control_rate;
  floorZ = -0.5 * h.voxel_size;
  terrainZ = decodeTerrain(h.terrain);
  if (floorGroup) { scene.remove(floorGroup); floorGroup = null; }
  $('title').textContent = `${h.name} (${h.kind}, ${h.task}${probe.mode === 'live' && h.live ? ', live' : probe.mode === 'export' ? ', exported replay' : ''})`;
  if (voxelMesh) scene.remove(voxelMesh);
  if (chamberMesh) scene.remove(chamberMesh);
  // Thesis colours: structural material semi-transparent, blue (hard) to red (soft); chambers
  // dark, drawn first so that they show through. Both deformed, as the still renderer draws them.
  surface = buildSurface(h);
  probe.surface = { vertices: surface.vertexCount, skinQuads: surface.skin.length, chamberQuads: surface.walls.length };
  voxelMesh = quadMesh(surface.skin, (item) => h.voxel_colours[item].map((c) => c / 255),
    new THREE.MeshLambertMaterial({ vertexColors: true, transparent: true, opacity: 0.5, depthWrite: false, side: THREE.DoubleSide }));
  voxelMesh.renderOrder = 2;
  scene.add(voxelMesh);
  if (h.chamber_cells > 0) {
    chamberMesh = quadMesh(surface.walls, () => [0.2, 0.2, 0.22],
      new THREE.MeshBasicMaterial({ vertexColors: true, transparent: true, opacity: 0.9, side: THREE.DoubleSide }));
    chamberMesh.renderOrder = 1;
    chamberMesh.visible = $('chambers').checked;
    scene.add(chamberMesh);
  }
  // The fabrication view (docs/fabrication.md): the inlet channels softevo fabricate cuts, one
  // box per wall voxel they pass through, in that voxel's frame; the body fades to show them.
  if (channelMesh) scene.remove(channelMesh);
  channelMesh = null;
  const segments = (h.fabrication && h.fabrication.channels) || [];
  if (segments.length > 0) {
    channelMesh = new THREE.InstancedMesh(new THREE.BoxGeometry(1, 1, 1),
      new THREE.MeshBasicMaterial({ color: 0xffc21a }), segments.length);
    channelMesh.renderOrder = 0;
    channelMesh.frustumCulled = false;
    scene.add(channelMesh);
  }
  showFabrication();
  const n = h.planned_records;
  pathLine && scene.remove(pathLine);
  const pathGeo = new THREE.BufferGeometry();
  pathGeo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(3 * n), 3));
  pathGeo.setDrawRange(0, 0);
  pathCount = 0;
  pathLast = -1;
  pathLine = new THREE.Line(pathGeo, new THREE.LineBasicMaterial({ color: 0x1a1a1a }));
  scene.add(pathLine);
  const chambers = [...Array(h.chambers).keys()];
  // The fitness plot shows the components in the fitness's own unit (a direction in degrees or
  // an angle in radians would only flatten the others); the table lists them all with units.
  fitnessSeries = h.component_names.map((_, i) => i)
    .filter((i) => !h.component_units || h.component_units[i] === h.fitness_unit);
  charts = {
    pressure: new StripChart($('plot-pressure'), 'chamber pressure', chambers.map((q) => `c${q}`), 'kPa', n),
    valves: new StripChart($('plot-valves'), 'valve commands (in/out)',
      chambers.flatMap((q) => [`c${q}in`, `c${q}out`]), '0..1', n),
    fitness: new StripChart($('plot-fitness'), 'fitness so far', ['fitness', ...fitnessSeries.map((i) => h.component_names[i])],
      h.fitness_unit || 'task units', n),
  };
  $('scrub').max = String(n - 1);
  // The dial steers a live simulation: an exported replay (or a trace) only shows its target.
  $('steering').style.display = h.directed && h.live && probe.mode === 'live' ? '' : 'none';
  $('save').style.display = h.live && probe.mode === 'live' ? '' : 'none';
  targetLine && scene.remove(targetLine);
  targetLine = null;
  lastCentroid = null;
  renderFitness(null);
}

// ---------------------------------------------------------------- deformed surface
// The body as the still renderer draws it (docs/rendering.md "Deformed voxels", render::body_surface):
// each voxel's corners follow its position, orientation and the strains of its links, and the
// corners neighbours share meet at their mean, so a stretched or inflated body is one body.
// Face order X+, X-, Y+, Y-, Z+, Z- (docs/model.md §2.1); corner c has bit 0 = +x, 1 = +y, 2 = +z.
const FACE_STEPS = [[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]];
function faceCorners(face) {
  const axis = face >> 1, side = face % 2 === 0 ? 1 : 0, u = (axis + 1) % 3, w = (axis + 2) % 3;
  return [[0, 0], [1, 0], [1, 1], [0, 1]].map(([a, b]) => (side << axis) | (a << u) | (b << w));
}

// The lattice of the hello's cells (voxels, then chamber cells): each item's 8 vertices, its
// face neighbours, and the faces drawn: the voxels' skin (towards an empty cell) and the chamber
// cells' faces towards anything but another chamber cell.
function buildSurface(h) {
  const v = h.voxels, items = v + h.chamber_cells, cells = h.cells;
  const key = (x, y, z) => (x * 4096 + y) * 4096 + z;
  const itemAt = new Map();
  for (let i = 0; i < items; i++) itemAt.set(key(cells[3 * i], cells[3 * i + 1], cells[3 * i + 2]), i);
  const vertexOf = new Map();
  const corner = new Int32Array(8 * items), neighbour = new Int32Array(6 * items);
  for (let i = 0; i < items; i++) {
    const [x, y, z] = [cells[3 * i], cells[3 * i + 1], cells[3 * i + 2]];
    for (let c = 0; c < 8; c++) {
      const k = key(x + (c & 1), y + ((c >> 1) & 1), z + (c >> 2));
      if (!vertexOf.has(k)) vertexOf.set(k, vertexOf.size);
      corner[8 * i + c] = vertexOf.get(k);
    }
    FACE_STEPS.forEach(([dx, dy, dz], f) => {
      const n = itemAt.get(key(x + dx, y + dy, z + dz));
      neighbour[6 * i + f] = n === undefined ? -1 : n;
    });
  }
  const skin = [], walls = [];
  for (let i = 0; i < items; i++)
    for (let f = 0; f < 6; f++) {
      const n = neighbour[6 * i + f];
      if (i < v ? n >= 0 : n >= v) continue;
      (i < v ? skin : walls).push({ item: i, vertex: faceCorners(f).map((c) => corner[8 * i + c]) });
    }
  return { voxels: v, items, vertexCount: vertexOf.size, corner, neighbour, skin, walls,
    vertices: new Float64Array(3 * vertexOf.size) };
}

// The vertices of a frame into surface.vertices [m]. Half extents from the link strains
// (§2.3: e = (R_N^T (p_P - p_N))_axis / s - 1, the whole strain on both halves, s/2 without a
// link), corners p + R (±h), each vertex the mean of the voxels' corners there, else of the
// chamber cells' (cubes of edge s where the server placed them).
function surfacePositions(S, f, s) {
  const n = S.vertexCount, sums = new Float64Array(6 * n), counts = new Int32Array(2 * n);
  const rot = new Float64Array(9 * S.items);
  for (let i = 0; i < S.items; i++) {
    let [w, x, y, z] = [f.quats[4 * i], f.quats[4 * i + 1], f.quats[4 * i + 2], f.quats[4 * i + 3]];
    const l = Math.hypot(w, x, y, z) || 1;
    w /= l; x /= l; y /= l; z /= l;
    // Row-major R: column a is the voxel's axis a in the world.
    rot.set([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], 9 * i);
  }
  const p = f.positions, half = [[0, 0], [0, 0], [0, 0]];
  for (let i = 0; i < S.items; i++) {
    const voxel = i < S.voxels;
    for (let a = 0; a < 3; a++)
      for (let side = 0; side < 2; side++) {
        half[a][side] = 0.5 * s;
        const m = voxel ? S.neighbour[6 * i + 2 * a + (1 - side)] : -1;
        if (m < 0 || m >= S.voxels) continue;
        const lo = side ? i : m, hi = side ? m : i;
        let along = 0;
        for (let k = 0; k < 3; k++) along += rot[9 * lo + 3 * k + a] * (p[3 * hi + k] - p[3 * lo + k]);
        half[a][side] = 0.5 * along;
      }
    for (let c = 0; c < 8; c++) {
      const o = [(c & 1) ? half[0][1] : -half[0][0], (c & 2) ? half[1][1] : -half[1][0], (c & 4) ? half[2][1] : -half[2][0]];
      const vtx = S.corner[8 * i + c], slot = voxel ? 0 : 1;
      for (let k = 0; k < 3; k++)
        sums[6 * vtx + 3 * slot + k] += p[3 * i + k] + rot[9 * i + 3 * k] * o[0] + rot[9 * i + 3 * k + 1] * o[1] + rot[9 * i + 3 * k + 2] * o[2];
      counts[2 * vtx + slot]++;
    }
  }
  for (let vtx = 0; vtx < n; vtx++) {
    const slot = counts[2 * vtx] > 0 ? 0 : 1;
    for (let k = 0; k < 3; k++) S.vertices[3 * vtx + k] = sums[6 * vtx + 3 * slot + k] / counts[2 * vtx + slot];
  }
}

// A mesh of quads (two triangles each, six vertices, colours per quad).
function quadMesh(quads, colourOf, material) {
  const geo = new THREE.BufferGeometry();
  const colour = new Float32Array(18 * quads.length);
  quads.forEach((q, k) => { const c = colourOf(q.item); for (let t = 0; t < 6; t++) colour.set(c, 18 * k + 3 * t); });
  geo.setAttribute('position', new THREE.BufferAttribute(new Float32Array(18 * quads.length), 3));
  geo.setAttribute('normal', new THREE.BufferAttribute(new Float32Array(18 * quads.length), 3));
  geo.setAttribute('color', new THREE.BufferAttribute(colour, 3));
  const mesh = new THREE.Mesh(geo, material);
  mesh.frustumCulled = false;  // the body moves far from where it started
  return mesh;
}

// Writes the quads' corners (triangles q0 q1 q2, q0 q2 q3) and one normal per quad (the cross
// product of its diagonals: a deformed face is not flat) into the mesh.
function placeQuads(mesh, quads, vertices) {
  const pos = mesh.geometry.attributes.position, nor = mesh.geometry.attributes.normal;
  const at = (vtx, k) => vertices[3 * vtx + k];
  quads.forEach((q, k) => {
    const [a, b, c, d] = q.vertex;
    const e = [0, 1, 2].map((i) => at(c, i) - at(a, i)), g = [0, 1, 2].map((i) => at(d, i) - at(b, i));
    const nx = e[1] * g[2] - e[2] * g[1], ny = e[2] * g[0] - e[0] * g[2], nz = e[0] * g[1] - e[1] * g[0];
    const l = Math.hypot(nx, ny, nz) || 1;
    [a, b, c, a, c, d].forEach((vtx, t) => {
      pos.setXYZ(6 * k + t, at(vtx, 0), at(vtx, 1), at(vtx, 2));
      nor.setXYZ(6 * k + t, nx / l, ny / l, nz / l);
    });
  });
  pos.needsUpdate = true;
  nor.needsUpdate = true;
}

function centroidOf(positions, count) {
  const c = new THREE.Vector3();
  for (let i = 0; i < count; i++) c.x += positions[3 * i], c.y += positions[3 * i + 1], c.z += positions[3 * i + 2];
  return c.multiplyScalar(1 / Math.max(count, 1));
}

function setView(name) {
  changed();
  const c = lastCentroid || start;
  const d = 0.45;
  const offsets = { side: [0, -d, 0.06], top: [0, -0.001, d], iso: [-0.6 * d, -0.6 * d, 0.45 * d] };
  const o = offsets[name] || offsets.side;
  controls.target.copy(c);
  camera.position.set(c.x + o[0], c.y + o[1], c.z + o[2]);
  controls.update();
}
// The fabrication box: channels shown, the body see-through, the chambers shown as cavities.
function showFabrication() {
  const on = $('fabrication').checked;
  if (channelMesh) channelMesh.visible = on;
  // Fainter skin and cavities while on (as render --cutaway draws them), the usual 0.5 and 0.9 off.
  if (voxelMesh) voxelMesh.material.opacity = on ? 0.15 : 0.5;
  if (chamberMesh) chamberMesh.material.opacity = on ? 0.6 : 0.9;
  if (on && chamberMesh) chamberMesh.visible = true;
  if (!on && chamberMesh) chamberMesh.visible = $('chambers').checked;
  probe.fabrication = { shown: on, channels: channelMesh ? channelMesh.count : 0,
    error: hello && hello.fabrication ? hello.fabrication.error || null : null };
}
$('fabrication').addEventListener('change', () => { showFabrication(); changed(); });
// The chambers can be hidden to see the body alone (and shown again).
$('chambers').addEventListener('change', () => { if (chamberMesh) chamberMesh.visible = $('chambers').checked; changed(); });
document.querySelectorAll('[data-view]').forEach((b) => b.addEventListener('click', () => setView(b.dataset.view)));

// Draws a frame: {index, time, items, positions (Float32Array), quats (Float32Array w,x,y,z),
// pressures, valves, components, fitness, cx, cy, heading, target, last}.
function showFrame(f) {
  changed();
  probe.frames++;
  lastFrame = f;
  probe.last = { index: f.index, time: f.time, fitness: f.fitness, cx: f.cx, cy: f.cy, heading: f.heading,
    target: f.target, last: f.last };
  const v = hello.voxels;
  if (f.index === 0 || !lastCentroid) {
    start = centroidOf(f.positions, v);
    if (!floorGroup || f.index === 0) buildFloor(start);
    if (!lastCentroid) { lastCentroid = start.clone(); setView('side'); }
  }
  surfacePositions(surface, f, hello.voxel_size);
  placeQuads(voxelMesh, surface.skin, surface.vertices);
  if (channelMesh) {
    // Each channel piece in its wall voxel's frame (hello.fabrication.channels).
    const at = new THREE.Vector3(), turn = new THREE.Quaternion(), place = new THREE.Matrix4();
    hello.fabrication.channels.forEach((seg, k) => {
      const i = seg.voxel;
      at.set(f.positions[3 * i], f.positions[3 * i + 1], f.positions[3 * i + 2]);
      turn.set(f.quats[4 * i + 1], f.quats[4 * i + 2], f.quats[4 * i + 3], f.quats[4 * i]).normalize();
      at.add(new THREE.Vector3(...seg.centre).applyQuaternion(turn));
      place.compose(at, turn, new THREE.Vector3(...seg.size));
      channelMesh.setMatrixAt(k, place);
    });
    channelMesh.instanceMatrix.needsUpdate = true;
  }
  if (chamberMesh) {
    placeQuads(chamberMesh, surface.walls, surface.vertices);
    // Darker the more inflated (1.0 -> 1.2 bar), as the still renderer does.
    const colour = chamberMesh.geometry.attributes.color;
    surface.walls.forEach((q, k) => {
      const p = f.pressures[hello.chamber_index[q.item - hello.voxels]];
      const inflation = Number.isFinite(p) ? Math.min(Math.max((p - 1e5) / 0.2e5, 0), 1) : 0;
      const g = 0.32 - 0.24 * inflation;
      for (let t = 0; t < 6; t++) colour.setXYZ(6 * k + t, g, g, g * 1.1);
    });
    colour.needsUpdate = true;
  }
  const c = centroidOf(f.positions, v);
  if (lastCentroid && $('follow').checked) {
    const delta = c.clone().sub(lastCentroid);
    camera.position.add(delta);
    controls.target.add(delta);
  }
  lastCentroid = c;
  // The floor follows a robot that walks more than 1 m from where it was laid.
  if (floorCentre && Math.hypot(c.x - floorCentre.x, c.y - floorCentre.y) > 1.0) buildFloor(c);
  // Centroid path on the floor: a point per new record (scrubbing back keeps what was walked).
  if (f.index > pathLast) {
    const p = pathLine.geometry.attributes.position;
    if (pathCount < p.count) {
      p.setXYZ(pathCount++, start.x + f.cx, start.y + f.cy, groundZ(start.x + f.cx, start.y + f.cy) + 0.0005);
      p.needsUpdate = true;
      pathLine.geometry.setDrawRange(0, pathCount);
      pathLine.geometry.computeBoundingSphere();
    }
    pathLast = f.index;
  }
  if (hello.directed) setTarget(f.target);
  charts.pressure.set(f.index, f.time, Array.from(f.pressures, (x) => (x - 1e5) / 1000));
  charts.valves.set(f.index, f.time, f.valves);
  charts.fitness.set(f.index, f.time, [f.fitness, ...fitnessSeries.map((i) => f.components[i])]);
  $('clock').textContent = `${f.time.toFixed(2)} s / ${duration.toFixed(2)} s`;
  if (probe.mode === 'live') $('scrub').value = String(f.index);
  renderFitness(f);
}

function renderFitness(f) {
  if (!hello) return;
  const rows = [];
  const num = (x) => (x === undefined || x === null ? '' : Number(x).toPrecision(6));
  const unit = (u) => (u ? ` [${u}]` : '');
  rows.push([`fitness so far${unit(hello.fitness_unit)}`, f ? num(f.fitness) : '']);
  hello.component_names.forEach((n, i) => rows.push([n + unit(hello.component_units && hello.component_units[i]), f ? num(f.components[i]) : '']));
  if (probe.ended && probe.ended.fitness !== undefined) rows.push(['final fitness (softevo)', num(probe.ended.fitness)]);
  if (hello.archived) {
    rows.push([`archived fitness (gen ${hello.archived.generation} id ${hello.archived.id})`, num(hello.archived.fitness)]);
    if (hello.archived.units > 1 && hello.archived.unit_fitness !== undefined)
      rows.push(['archived fitness of unit 0 (shown)', num(hello.archived.unit_fitness)]);
  }
  if (hello.trace_fitness !== undefined) rows.push(['traced fitness', num(hello.trace_fitness)]);
  // Built as nodes with textContent: no name from a file or server ever becomes markup.
  const table = document.createElement('table');
  for (const r of rows) {
    const tr = table.insertRow();
    for (const cell of r) tr.insertCell().textContent = String(cell);
  }
  $('fitness').replaceChildren(table);
}

function ended(e) {
  probe.ended = e;
  const killed = e.status !== 'ok';
  const banner = $('banner');
  banner.style.display = killed ? 'block' : 'none';
  if (killed) banner.textContent = `${e.status.replace('_', ' ')} at ${Number(e.time).toFixed(2)} s${e.message ? ': ' + e.message : ''}`;
  $('status').textContent = ` ${e.status}, fitness ${Number(e.fitness ?? 0).toPrecision(8)}`;
  renderFitness(lastFrame);
}

// ---------------------------------------------------------------- steering dial
const dial = $('dial');
let dialDeg = 0;
function drawDial() {
  const dpr = window.devicePixelRatio || 1, w = dial.clientWidth || 110;
  dial.width = w * dpr; dial.height = w * dpr;
  const g = dial.getContext('2d');
  g.setTransform(dpr, 0, 0, dpr, 0, 0);
  const r = w / 2 - 4;
  g.clearRect(0, 0, w, w);
  g.strokeStyle = '#999';
  g.beginPath(); g.arc(w / 2, w / 2, r, 0, 2 * Math.PI); g.stroke();
  g.fillStyle = '#999'; g.font = '9px sans-serif';
  g.fillText('+x', w - 16, w / 2 - 3);
  const a = dialDeg * Math.PI / 180;
  g.strokeStyle = '#dd1414'; g.lineWidth = 3;
  g.beginPath(); g.moveTo(w / 2, w / 2); g.lineTo(w / 2 + r * Math.cos(a), w / 2 - r * Math.sin(a)); g.stroke();
}
function steerTo(deg) {
  deg = Math.max(-180, Math.min(180, deg));
  send({ type: 'steer', deg: Math.round(deg) });
}
function dialEvent(ev) {
  const b = dial.getBoundingClientRect();
  const x = ev.clientX - b.left - b.width / 2, y = b.top + b.height / 2 - ev.clientY;
  steerTo(Math.atan2(y, x) * 180 / Math.PI);
}
dial.addEventListener('pointerdown', (ev) => { dial.setPointerCapture(ev.pointerId); dialEvent(ev); });
dial.addEventListener('pointermove', (ev) => { if (ev.buttons) dialEvent(ev); });
// Shift+drag on the floor: the direction from the start towards the pointer.
const raycaster = new THREE.Raycaster();
renderer.domElement.addEventListener('pointerdown', (ev) => { if (ev.shiftKey) controls.enabled = false; });
renderer.domElement.addEventListener('pointerup', () => { controls.enabled = true; });
renderer.domElement.addEventListener('pointermove', (ev) => {
  if (!ev.shiftKey || !ev.buttons || !hello || !hello.directed) return;
  const b = renderer.domElement.getBoundingClientRect();
  raycaster.setFromCamera(new THREE.Vector2(((ev.clientX - b.left) / b.width) * 2 - 1, -((ev.clientY - b.top) / b.height) * 2 + 1), camera);
  const hit = new THREE.Vector3();
  if (raycaster.ray.intersectPlane(new THREE.Plane(new THREE.Vector3(0, 0, 1), -floorZ), hit))
    steerTo(Math.atan2(hit.y - start.y, hit.x - start.x) * 180 / Math.PI);
});

// ---------------------------------------------------------------- sources
let send = () => {};
let playing = true;

function decodeLiveFrame(buf) {
  const dv = new DataView(buf);
  if (dv.getUint32(0, true) !== 0x31465653) throw new Error('not a softevo frame');
  const items = dv.getUint32(8, true), chambers = dv.getUint16(12, true), nc = dv.getUint16(14, true);
  let o = 48;
  const positions = new Float32Array(buf, o, 3 * items); o += 12 * items;
  const q16 = new Int16Array(buf, o, 4 * items); o += 8 * items;
  const quats = Float32Array.from(q16, (x) => x / 32767);
  const pressures = new Float32Array(buf, o, chambers); o += 4 * chambers;
  const valves = new Float32Array(buf, o, 2 * chambers); o += 8 * chambers;
  const components = new Float32Array(buf, o, nc);
  return { index: dv.getUint32(4, true), time: dv.getFloat64(16, true), items, positions, quats, pressures,
    valves, components, fitness: dv.getFloat32(24, true), cx: dv.getFloat32(28, true), cy: dv.getFloat32(32, true),
    heading: dv.getFloat32(36, true), target: dv.getFloat32(40, true), last: (dv.getUint32(44, true) & 1) === 1 };
}

function startLive() {
  probe.mode = 'live';
  const ws = new WebSocket(`ws://${location.host}/ws`);
  ws.binaryType = 'arraybuffer';
  probe.socket = ws;
  send = (m) => { if (ws.readyState === 1) ws.send(JSON.stringify(m)); };
  ws.onmessage = (ev) => {
    if (typeof ev.data !== 'string') {
      probe.bytes += ev.data.byteLength;
      const f = decodeLiveFrame(ev.data);
      showFrame(f);
      return;
    }
    probe.bytes += ev.data.length;
    const m = JSON.parse(ev.data);
    if (m.type === 'hello') setup(m);
    else if (m.type === 'ended') ended(m);
    else if (m.type === 'terrain') groundChanged(m.terrain);
    else if (m.type === 'error') { probe.errors.push(m.message); $('note').textContent = 'server: ' + m.message; }
    else if (m.type === 'saved') { probe.saved = m; $('note').textContent = `saved ${m.trace} and ${m.steering} (in the server's --save-dir)`; }
    else if (m.type === 'state') { playing = m.playing; $('play').textContent = playing ? 'Pause' : 'Play'; }
  };
  ws.onclose = () => { $('note').textContent = 'disconnected from softevo view'; };
  $('play').onclick = () => send({ type: playing ? 'pause' : 'play' });
  $('step').onclick = () => send({ type: 'step' });
  $('reset').onclick = () => {
    probe.ended = null; $('banner').style.display = 'none'; $('status').textContent = '';
    if (charts) Object.values(charts).forEach((c) => c.clear());
    pathLine && pathLine.geometry.setDrawRange(0, 0);
    pathCount = 0;
    pathLast = -1;
    send({ type: 'reset' });
  };
  $('speed').onchange = () => send({ type: 'speed', value: Number($('speed').value) });
  $('scrub').oninput = () => send({ type: 'seek', frame: Number($('scrub').value) });
  $('save').onclick = () => send({ type: 'save' });
}

// Byte planes back to 4-byte values (see view/export_html.hpp).
function planes(bytes, offset, n, Type) {
  const out = new Uint8Array(4 * n);
  for (let k = 0; k < 4; k++) for (let i = 0; i < n; i++) out[4 * i + k] = bytes[offset + k * n + i];
  return new Type(out.buffer);
}

async function startEmbedded(el) {
  probe.mode = 'export';
  setup(JSON.parse($('softevo-hello').textContent));
  const endNote = JSON.parse($('softevo-ended').textContent);
  const raw = Uint8Array.from(atob(el.textContent.trim()), (c) => c.charCodeAt(0));
  const inflated = new Uint8Array(await new Response(new Blob([raw]).stream().pipeThrough(new DecompressionStream('deflate'))).arrayBuffer());
  const dv = new DataView(inflated.buffer);
  if (dv.getUint32(0, true) !== 0x31585653) throw new Error('embedded frames: bad magic');
  const F = dv.getUint32(4, true), N = dv.getUint32(8, true), C = dv.getUint16(12, true), K = dv.getUint16(14, true);
  const quantum = dv.getFloat32(16, true);
  let o = 20;
  const time = planes(inflated, o, F, Float32Array); o += 4 * F;
  const dpos = planes(inflated, o, F * N * 3, Int32Array); o += 12 * F * N;
  const dori = new Uint8Array(inflated.buffer, o, F * N * 4); o += 4 * F * N;
  const pressures = planes(inflated, o, F * C, Float32Array); o += 4 * F * C;
  const valves = new Uint8Array(inflated.buffer, o, F * 2 * C); o += 2 * F * C;
  const comps = planes(inflated, o, F * K, Float32Array); o += 4 * F * K;
  const series = [];
  for (let s = 0; s < 5; s++) { series.push(planes(inflated, o, F, Float32Array)); o += 4 * F; }
  const frames = [];
  const accP = new Int32Array(3 * N), accO = new Uint8Array(4 * N);
  for (let f = 0; f < F; f++) {
    const positions = new Float32Array(3 * N), quats = new Float32Array(4 * N);
    for (let i = 0; i < 3 * N; i++) { accP[i] += dpos[f * 3 * N + i]; positions[i] = accP[i] * quantum; }
    for (let i = 0; i < 4 * N; i++) { accO[i] = (accO[i] + dori[f * 4 * N + i]) & 255; quats[i] = ((accO[i] << 24) >> 24) / 127; }
    frames.push({ index: Math.round(time[f] * hello.control_rate), time: time[f], items: N, positions, quats,
      pressures: pressures.subarray(f * C, (f + 1) * C), valves: Float32Array.from(valves.subarray(f * 2 * C, (f + 1) * 2 * C), (u) => u / 255),
      components: comps.subarray(f * K, (f + 1) * K), fitness: series[0][f], cx: series[1][f], cy: series[2][f],
      heading: series[3][f], target: series[4][f], last: f === F - 1 });
  }
  probe.embeddedFrames = F;
  let shown = -1, playTime = 0, speed = 1;
  const show = (k) => {
    k = Math.max(0, Math.min(F - 1, k));
    if (k === shown) return;
    if (k < shown) { charts && Object.values(charts).forEach((c) => { c.cursor = -1; c.dirty = true; }); }
    shown = k;
    showFrame(frames[k]);
    if (k === F - 1) ended(endNote);
  };
  $('scrub').max = String(F - 1);
  const seek = (k) => { show(k); playTime = frames[shown].time; };
  $('play').onclick = () => { playing = !playing; if (playing && shown === F - 1) seek(0); $('play').textContent = playing ? 'Pause' : 'Play'; };
  $('step').onclick = () => { playing = false; $('play').textContent = 'Play'; seek(shown + 1); };
  $('reset').onclick = () => seek(0);
  $('speed').onchange = () => { speed = Number($('speed').value); };
  $('scrub').oninput = () => seek(Number($('scrub').value));
  // The scrubber counts exported frames here, not records.
  seek(0);
  let t0 = performance.now();
  const tick = (now) => {
    const dt = Math.min((now - t0) / 1000, 1); t0 = now;
    if (playing) {
      playTime += dt * speed;
      let k = Math.max(shown, 0);
      while (k + 1 < F && frames[k + 1].time <= playTime) k++;
      show(k);
      $('scrub').value = String(shown);
      if (shown === F - 1) { playing = false; $('play').textContent = 'Play'; }
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
}

// ---------------------------------------------------------------- WebM recording
let recorder = null;
$('record').onclick = () => {
  if (recorder) { recorder.stop(); return; }
  const chunks = [];
  recorder = new MediaRecorder(renderer.domElement.captureStream(30), { mimeType: 'video/webm' });
  recorder.ondataavailable = (e) => e.data.size && chunks.push(e.data);
  recorder.onstop = () => {
    const a = document.createElement('a');
    a.href = URL.createObjectURL(new Blob(chunks, { type: 'video/webm' }));
    a.download = `${hello ? hello.name.replace(/[^A-Za-z0-9_-]+/g, '_') : 'softevo'}.webm`;
    a.click();
    probe.recorded = chunks.reduce((n, c) => n + c.size, 0);
    recorder = null;
    $('record').textContent = 'Record WebM';
  };
  recorder.start(250);
  $('record').textContent = 'Stop recording';
};

// ---------------------------------------------------------------- render loop
let fpsCount = 0, fpsStart = performance.now(), plotsDrawn = 0;
function animate(now) {
  requestAnimationFrame(animate);
  if (redraw || recorder) {
    redraw = false;
    renderer.render(scene, camera);
    probe.renders++;
    probe.renderedIndex = lastFrame ? lastFrame.index : -1;
    fpsCount++;
  }
  if (now - fpsStart >= 1000) { probe.fps = (fpsCount * 1000) / (now - fpsStart); fpsCount = 0; fpsStart = now; }
  // The plots at 5 Hz: hundreds of series points are not worth redrawing every frame.
  if (charts && now - plotsDrawn > 200) {
    plotsDrawn = now;
    for (const c of Object.values(charts)) c.draw(duration);
  }
}
resize();
drawDial();
requestAnimationFrame(animate);
const embedded = $('softevo-frames');
if (embedded) startEmbedded(embedded).catch((e) => { probe.errors.push(String(e)); $('note').textContent = String(e); });
else startLive();
