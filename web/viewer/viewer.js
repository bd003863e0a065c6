// pmz web viewer: streams a .pmz (?src=URL, the URL box, or a dropped file) into a three.js
// scene and refines it while the bytes arrive, within a per-frame time budget.
import * as THREE from 'three';
import { OrbitControls } from './vendor/OrbitControls.js';
import { PMZLoader, geomorphMaterial, pmzMaterials } from 'pmz-decoder/three';

// Decoding runs in a Web Worker (?worker=0: on this thread, REFINE_BUDGET_MS of splits per frame).
const REFINE_BUDGET_MS = 8;  // of a 16.7 ms frame: rendering and feeding keep the rest
const params = new URLSearchParams(location.search);
const useWorker = params.get('worker') !== '0' && typeof Worker === 'function';
const BACKGROUND = 0x20242a;

// MSAA about doubles a frame's cost in a software renderer (SwiftShader, 75k-face bunny at load
// 15: median frame gap 283 ms with, 117 ms without): off there, on elsewhere; ?aa=0/1 decides.
function softwareRenderer() {
  try {
    const gl = document.createElement('canvas').getContext('webgl2');
    const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
    const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
    const lose = gl && gl.getExtension('WEBGL_lose_context');
    if (lose) lose.loseContext();
    return /swiftshader|llvmpipe|softpipe|software/i.test(name);
  } catch (e) {
    return false;
  }
}
const software = softwareRenderer();
const antialias = params.has('aa') ? params.get('aa') !== '0' : !software;
const renderer = new THREE.WebGLRenderer({ antialias, preserveDrawingBuffer: true });
// A software renderer shades every device pixel on the CPU: CSS pixels there.
renderer.setPixelRatio(software ? 1 : window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
renderer.setClearColor(BACKGROUND);
document.body.prepend(renderer.domElement);
const scene = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.01, 100);
camera.position.set(0, 0, 3);
scene.add(camera);
scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.2));
const light = new THREE.DirectionalLight(0xffffff, 2.0);
light.position.set(1, 1.5, 2);
camera.add(light);
const controls = new OrbitControls(camera, renderer.domElement);
// Frames are drawn when something changed (geometry, view, material, a texture arrived, new
// vertices still gliding): redrawing an unchanged scene only takes CPU from the decoder, and
// a software renderer needs a good part of a second for a large mesh on a loaded machine.
let redraw = true, glideUntil = 0;
const requestRedraw = () => { redraw = true; };
controls.addEventListener('change', requestRedraw);

const material = new THREE.MeshStandardMaterial({ color: 0xd8c8a8, flatShading: true,
  side: THREE.DoubleSide, roughness: 0.7 });
const GLIDE_SECONDS = 0.4;
const morphClock = geomorphMaterial(material, GLIDE_SECONDS);
let morphTime = null;  // tests: a fixed geomorph time instead of the clock
const plainMaterial = new THREE.MeshStandardMaterial({ color: 0xd8c8a8, flatShading: true,
  side: THREE.DoubleSide, roughness: 0.7 });

// Frame-time budget for drawing while a stream decodes (?drawms=N, 0: off): where drawing is
// the limit (a software renderer draws 75k faces in about 50 ms on a loaded 2-core machine),
// the stream shows at most as many faces as the measured cost per face lets it draw in
// DRAW_BUDGET_MS (of the 50 ms a frame may take: the rest is the page's own work and the
// frame's alignment); the finest level is shown once decoding ends (PMZStream.faceLimit).
// The cost per face starts from a calibration draw before the stream opens and follows the
// frames' timestamps. The calibration draws while nothing decodes: during the stream the
// decoding worker takes a core SwiftShader would otherwise use, and faces once shown cannot be
// taken back while decoding. So the shown faces grow in steps frames have proven: at most
// GROWTH x the most faces a frame drew within DRAW_BUDGET_MS (at least GROWTH_START_FACES).
// A frame that took longer than SLOW_FRAME_MS after drawing F >= MIN_SAMPLE_FACES faces is a sample gap / F
// (the median of the last five is the estimate), a faster one bounds the cost by gap / F. A
// machine too busy to keep even the frames that draw nothing at the display's rate is not
// drawing's doing: what their gaps (median of the last nine) exceed a vsync by is taken off
// the drawn frames' gaps first. ?maxfaces=N caps the faces shown while decoding outright.
const DRAW_BUDGET_MS = params.has('drawms') ? Number(params.get('drawms')) : 30;
const MAX_FACES = params.has('maxfaces') ? Number(params.get('maxfaces')) : Infinity;
const SLOW_FRAME_MS = 25;
const MIN_SAMPLE_FACES = 1000;
const VSYNC_MS = 1000 / 60;
// ?drawgrowth=N: the factor (0: no such bound, the calibrated limit at once).
const GROWTH = params.has('drawgrowth') ? Number(params.get('drawgrowth')) : 2, GROWTH_START_FACES = 2000;
// ms per face; the last drawn frame; the previous frame's time; gaps after frames that drew
// nothing; the most faces a frame drew within the budget
const drawCost = { perFace: 0, samples: [], last: null, prev: null, idle: [], proven: 0, lastDrawing: 0 };
function noteFrame(t) {
  const last = drawCost.last, gap = drawCost.prev === null ? 0 : t - drawCost.prev;
  drawCost.last = null;
  drawCost.prev = t;
  if (!last) {
    if (gap > 0) {
      drawCost.idle.push(gap);
      if (drawCost.idle.length > 9) drawCost.idle.shift();
    }
    return;
  }
  if (last.faces === 0) return;
  const idle = [...drawCost.idle].sort((a, b) => a - b);
  const busy = idle.length ? Math.max(0, idle[idle.length >> 1] - VSYNC_MS) : 0;
  const drawing = Math.max(VSYNC_MS, gap - busy), sample = drawing / last.faces;
  drawCost.lastDrawing = drawing;
  if (drawing <= DRAW_BUDGET_MS) drawCost.proven = Math.max(drawCost.proven, last.faces);
  if (drawing > SLOW_FRAME_MS) {
    if (last.faces < MIN_SAMPLE_FACES) return;  // then mostly the frame's fixed costs
    drawCost.samples.push(sample);
    if (drawCost.samples.length > 5) drawCost.samples.shift();
    const sorted = [...drawCost.samples].sort((a, b) => a - b);
    drawCost.perFace = sorted.length >= 3 ? sorted[sorted.length >> 1] : Math.max(drawCost.perFace, sample);
  } else {
    drawCost.perFace = Math.min(drawCost.perFace || sample, sample);
  }
}
// ?yielddraw=1 (an experiment, off by default): each drawn frame while decoding asks the
// decoding worker to pause for about the last drawn frame's time (at most 40 ms, at most half
// the time), so that a CPU renderer (SwiftShader) has the cores the worker would take.
const YIELD_DRAW = params.get('yielddraw') === '1';
let yieldAgain = 0;  // performance.now() before which no new pause is asked for

// The face limit for the stream now (null: none).
function faceLimit(shownFaces, fullFaces) {
  let limit = MAX_FACES;
  if (DRAW_BUDGET_MS > 0 && drawCost.perFace > 0) {
    const proven = GROWTH > 0 ? GROWTH * Math.max(drawCost.proven, GROWTH_START_FACES / GROWTH) : Infinity;
    limit = Math.min(limit, Math.max(shownFaces, Math.floor(Math.min(proven, DRAW_BUDGET_MS / drawCost.perFace))));
  }
  return limit >= fullFaces ? null : limit;
}

// Both materials' shader programs are compiled before a stream is opened (in parallel where
// the browser has KHR_parallel_shader_compile): compiling on the first frame with the object
// blocked the page for seconds in SwiftShader. Then one tiny triangle is drawn with each, as
// the streams are (indexed, 32-bit indices): SwiftShader generates its drawing code for a
// state at its first draw, which should not be the first frame with the object.
const shadersReady = (async () => {
  const dummy = new THREE.BufferGeometry();
  dummy.setAttribute('position', new THREE.BufferAttribute(new Float32Array([0, 0, 0, 1e-4, 0, 0, 0, 1e-4, 0]), 3));
  dummy.setAttribute('pmzMorph', new THREE.BufferAttribute(new Float32Array(12), 4));
  dummy.setIndex(new THREE.BufferAttribute(new Uint32Array([0, 1, 2]), 1));
  const meshes = [material, plainMaterial].map((m) => new THREE.Mesh(dummy, m));
  for (const m of meshes) {
    m.frustumCulled = false;
    scene.add(m);
  }
  try {
    await renderer.compileAsync(scene, camera);
    renderer.render(scene, camera);
    if (DRAW_BUDGET_MS > 0) calibrate(meshes[0]);
  } finally {
    for (const m of meshes) scene.remove(m);
    dummy.dispose();
    redraw = true;
  }
})();

// The first estimate of the cost per face: CALIBRATION_FACES small triangles (a grid over part
// of the view, as a streamed mesh covers it) drawn with the geomorph material, timed to a
// one-pixel readPixels (the draw has then happened); the second of two draws (the first
// uploads).
const CALIBRATION_FACES = 20000;
function calibrate(mesh) {
  const n = Math.ceil(Math.sqrt(CALIBRATION_FACES / 2)), positions = new Float32Array(3 * (n + 1) * (n + 1));
  for (let i = 0, k = 0; i <= n; ++i)
    for (let j = 0; j <= n; ++j, k += 3) positions.set([(j / n - 0.5) * 1.2, (i / n - 0.5) * 1.2, 0], k);
  const index = new Uint32Array(6 * n * n);
  for (let i = 0, k = 0; i < n; ++i)
    for (let j = 0; j < n; ++j, k += 6) {
      const a = i * (n + 1) + j, b = a + n + 1;
      index.set([a, a + 1, b, a + 1, b + 1, b], k);
    }
  const grid = new THREE.BufferGeometry();
  grid.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  const glide = new Float32Array(4 * (n + 1) * (n + 1));  // born long ago: at their positions
  for (let v = 0; v <= (n + 1) * (n + 1) - 1; ++v) glide.set([...positions.subarray(3 * v, 3 * v + 3), -1e6], 4 * v);
  grid.setAttribute('pmzMorph', new THREE.BufferAttribute(glide, 4));
  grid.setIndex(new THREE.BufferAttribute(index, 1));
  const saved = mesh.geometry, gl = renderer.getContext(), pixel = new Uint8Array(4);
  mesh.geometry = grid;
  let ms = 0;
  for (let i = 0; i < 2; ++i) {
    const t0 = performance.now();
    renderer.render(scene, camera);
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
    ms = performance.now() - t0;
  }
  mesh.geometry = saved;
  grid.dispose();
  drawCost.perFace = ms / (2 * n * n);
  window.pmzDrawCalibration = { faces: 2 * n * n, ms };
}

const overlay = document.getElementById('overlay');
const lod = document.getElementById('lod');
const morph = document.getElementById('morph');

// State for tests and scripts: window.pmzStatus, plus timings (performance.now() ms) and one
// entry per animation frame.
const status = { faces: 0, vertices: 0, bytes: 0, totalBytes: 0, complete: false, error: '' };
window.pmzStatus = status;
window.pmzTiming = { firstBytes: null, firstObjectFrame: null };
window.pmzFrames = [];
// Main-thread tasks over 50 ms (Long Tasks API, where supported): {start, duration}.
window.pmzLongTasks = [];
if (typeof PerformanceObserver === 'function' &&
    (PerformanceObserver.supportedEntryTypes || []).includes('longtask')) {
  new PerformanceObserver((list) => {
    for (const e of list.getEntries()) window.pmzLongTasks.push({ start: e.startTime, duration: e.duration });
  }).observe({ type: 'longtask' });
}

// Streams with attributes (texture coordinates, normals, colours, materials) are drawn with
// pmzMaterials(): textured, lit with their normals; each with a geomorph twin.
function dress(stream) {
  const plain = pmzMaterials(stream, {
    onTextureLoad: requestRedraw,
    onTextureError: (url) => console.warn(`pmz viewer: texture ${url} not loaded; drawn untextured`),
  });
  const morphing = plain.map((m) => {
    const twin = m.clone();
    morphTicks.push(geomorphMaterial(twin, GLIDE_SECONDS));
    return twin;
  });
  const one = (a) => (a.length === 1 ? a[0] : a);  // an array draws only the geometry's groups
  return { plain: one(plain), morph: one(morphing) };
}
let morphTicks = [];  // geomorph clocks of the dressed materials

// Compiles the programs of materials ({plain, morph}, each one or an array) for a geometry,
// in parallel where the browser can (KHR_parallel_shader_compile), lit as the scene is.
function compileFirst(materials, geometry) {
  const probe = new THREE.Group();
  for (const m of [materials.plain, materials.morph].flat()) probe.add(new THREE.Mesh(geometry, m));
  return renderer.compileAsync(probe, camera, scene).catch((e) => console.warn(`pmz viewer: ${e}`));
}

let current = null;  // { stream, mesh, fitted, materials }
let faceTarget = null;  // null: follow the stream; else the LOD slider's face count
lod.addEventListener('input', () => {
  const v = Number(lod.value);
  const full = current ? current.stream.info().fullFaces : 0;
  faceTarget = v >= 1000 ? null : Math.max(1, Math.round(full * (v / 1000) ** 2));
});
let rate = { t: performance.now(), splits: 0, perSecond: 0 };

function setError(message) {
  status.error = String(message).split('\n')[0];
}

async function open(source) {
  if (current) {
    scene.remove(current.mesh);
    current.stream.dispose();
    if (current.materials && current.materials.plain !== plainMaterial) {
      for (const m of [current.materials.plain, current.materials.morph].flat()) {
        if (m.map) m.map.dispose();
        m.dispose();
      }
    }
    current = null;
    redraw = true;
  }
  morphTicks = [];
  Object.assign(status, { faces: 0, vertices: 0, bytes: 0, totalBytes: 0, complete: false, error: '' });
  window.pmzTiming = { firstBytes: null, firstObjectFrame: null };
  window.pmzFrames = [];
  window.pmzLongTasks = [];
  drawCost.proven = 0;
  try {
    await shadersReady;  // and the draw calibration: the first face limit
    const loader = new PMZLoader(undefined, { geomorph: true, autoUpdate: false, worker: useWorker,
      faceLimit: faceLimit(0, Infinity) });
    const stream = await loader.stream(source, (s) => {
      if (window.pmzTiming.firstBytes === null && s.bytes > 0) window.pmzTiming.firstBytes = performance.now();
      status.bytes = s.bytes;
      status.totalBytes = s.totalBytes;
    });
    const mesh = new THREE.Mesh(stream.geometry, morph.checked ? material : plainMaterial);
    mesh.frustumCulled = false;
    scene.add(mesh);
    redraw = true;
    current = { stream, mesh, fitted: false, materials: null };
    const result = await stream.done;
    if (result !== 'ok') setError(stream.error || result);
  } catch (e) {
    setError(e && e.message ? e.message : e);
  }
}

function fit(info) {
  const min = new THREE.Vector3(...info.bboxMin), max = new THREE.Vector3(...info.bboxMax);
  const center = min.clone().add(max).multiplyScalar(0.5);
  const radius = Math.max(1e-6, max.distanceTo(min) / 2);
  const distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
  controls.target.copy(center);
  camera.position.copy(center).add(new THREE.Vector3(0.35, 0.3, 1).normalize().multiplyScalar(distance));
  camera.near = distance / 100;
  camera.far = distance * 10;
  camera.updateProjectionMatrix();
  controls.update();
}

function frame(t) {
  const tStart = performance.now();
  requestAnimationFrame(frame);
  noteFrame(t);
  let work = 0;  // ms spent in update(): refinement on this thread, or applying the worker's
  let limit = null;
  if (current) {
    const s = current.stream;
    const info = s.info();
    if (info.baseDone && !current.fitted) {
      fit(info);
      current.fitted = true;
    }
    const before = s.splitsApplied;
    s.faceTarget = faceTarget;
    s.faceLimit = limit = faceLimit(s.faceCount, info.headerDone ? info.fullFaces : Infinity);
    const t0 = performance.now();
    if (s.update(REFINE_BUDGET_MS)) {
      redraw = true;
      glideUntil = performance.now() + 1000 * GLIDE_SECONDS + 50;
    }
    work = performance.now() - t0;
    const g = s.geometry;
    if (!current.materials && !current.dressing && g.getAttribute('position')) {
      const attributes = ['uv', 'normal', 'color'].some((n) => g.getAttribute(n)) || s.materials().length > 1;
      if (attributes) {
        // The dressed materials' programs are compiled before they draw (the plain ones draw
        // meanwhile): compiling at their first draw blocked the page.
        const dressed = dress(s), c = current;
        c.dressing = true;
        compileFirst(dressed, g).then(() => {
          c.materials = dressed;
          redraw = true;
        });
      } else {
        current.materials = { plain: plainMaterial, morph: material };
      }
      // Tests: the attributes the geometry draws with, and how many materials.
      window.pmzAttributes = { names: ['uv', 'uv1', 'normal', 'color'].filter((n) => g.getAttribute(n)),
        materials: s.materials().length };
    }
    rate.splits += Math.max(0, s.splitsApplied - before);
    if (window.pmzTiming.firstBytes === null && s.firstBytesTime != null)
      window.pmzTiming.firstBytes = s.firstBytesTime;
    Object.assign(status, { bytes: s.bytes, totalBytes: s.totalBytes });
    Object.assign(status, { faces: s.faceCount, vertices: s.vertexCount, complete: s.complete });
    if (s.status !== 'ok') setError(s.error);
    const m = current.materials && (morph.checked ? current.materials.morph : current.materials.plain);
    if (m && current.mesh.material !== m) {
      current.mesh.material = m;
      redraw = true;
    }
  }
  if (morphTime === null) {
    morphClock();
    for (const tick of morphTicks) tick();
  }
  controls.update();
  const t0r = performance.now();
  const drawn = redraw || (morph.checked && t0r < glideUntil);
  if (drawn && YIELD_DRAW && current && current.stream.pauseDecoding && status.faces > 0 && !status.complete &&
      t0r >= yieldAgain) {
    const ms = Math.min(40, Math.max(VSYNC_MS, drawCost.lastDrawing || VSYNC_MS));
    current.stream.pauseDecoding(ms);
    yieldAgain = t0r + 2 * ms;
  }
  if (drawn) renderer.render(scene, camera);
  redraw = false;
  const now = performance.now();
  if (drawn && status.faces > 0 && window.pmzTiming.firstObjectFrame === null) {
    window.pmzTiming.firstObjectFrame = now;
    window.pmzTiming.firstObjectFaces = status.faces;
  }
  if (drawn) drawCost.last = { t, faces: status.faces };
  if (window.pmzFrames.length < 100000) {
    window.pmzFrames.push({ t, faces: status.faces, bytes: status.bytes, work, render: now - t0r, drawn,
      limit, decoded: current ? current.stream.decodedFaces : 0, js: 0 });
  }
  if (now - rate.t >= 500) {
    rate = { t: now, splits: 0, perSecond: rate.splits / ((now - rate.t) / 1000) };
  }
  const kb = (n) => (n / 1024).toFixed(1) + ' KiB';
  const text = current
    ? `faces     ${status.faces.toLocaleString()}` +
      (limit !== null && !status.complete ? ` shown (draw budget), ${current.stream.decodedFaces.toLocaleString()} ` +
        'decoded' : '') + `\nvertices  ${status.vertices.toLocaleString()}\n` +
      `bytes     ${kb(status.bytes)} / ${status.totalBytes ? kb(status.totalBytes) : '?'}\n` +
      `refine    ${Math.round(rate.perSecond).toLocaleString()} splits/s\n` +
      (status.error ? `error     ${status.error}` : status.complete ? 'complete' : 'streaming')
    : overlay.textContent;
  if (text !== overlay.textContent) overlay.textContent = text;  // no layout for an unchanged text
  // The whole callback's time (update, render() call, overlay): the page's own JS per frame.
  if (window.pmzFrames.length) window.pmzFrames[window.pmzFrames.length - 1].js = performance.now() - tStart;
}
requestAnimationFrame(frame);

window.addEventListener('resize', () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  redraw = true;
});

// Tests: hold a face count (null follows the stream), and the canvas's coverage (share of
// pixels not the background) with a downsampled copy for comparing two frames.
window.pmzSetFaces = (faces) => {
  faceTarget = faces;
  const full = current ? current.stream.info().fullFaces : 0;
  lod.value = faces === null ? 1000 : Math.min(999, Math.round(1000 * Math.sqrt(faces / Math.max(1, full))));
};
function snapshot() {
  const w = 200, h = Math.round(200 * renderer.domElement.height / renderer.domElement.width);
  const c = document.createElement('canvas');
  c.width = w; c.height = h;
  const g = c.getContext('2d');
  g.drawImage(renderer.domElement, 0, 0, w, h);
  const px = g.getImageData(0, 0, w, h).data;
  const bg = new THREE.Color(BACKGROUND);
  const br = Math.round(bg.r * 255), bgg = Math.round(bg.g * 255), bb = Math.round(bg.b * 255);
  let covered = 0;
  for (let i = 0; i < px.length; i += 4)
    if (Math.abs(px[i] - br) + Math.abs(px[i + 1] - bgg) + Math.abs(px[i + 2] - bb) > 24) ++covered;
  return { coverage: covered / (w * h), pixels: Array.from(px) };
}
window.pmzSnapshot = () => {
  renderer.render(scene, camera);
  return snapshot();
};
// The same view drawn from a geometry built afresh from the decoder's current buffers: what
// the in-place updated geometry must look like.
window.pmzReferenceSnapshot = async () => {
  const d = (await current.stream.snapshot()).render, streamed = current.mesh.geometry;
  const fresh = new THREE.BufferGeometry();
  fresh.setAttribute('position', new THREE.BufferAttribute(d.positions, 3));
  for (const [name, size] of d.layout) fresh.setAttribute(name, new THREE.BufferAttribute(d.attributes[name], size));
  fresh.setIndex(new THREE.BufferAttribute(d.indices, 1));
  for (const group of streamed.groups) fresh.addGroup(group.start, group.count, group.materialIndex);
  current.mesh.geometry = fresh;
  current.mesh.material = current.materials ? current.materials.plain : plainMaterial;
  renderer.render(scene, camera);
  const shot = snapshot();
  current.mesh.geometry = streamed;
  fresh.dispose();
  return shot;
};

// Tests: the geomorph shader at time T (seconds) against the same blend computed here from the
// geometry's pmzMorph attribute and drawn without geomorphs. Returns both snapshots and how
// many vertices sit at their parent (blend 0), between, and at their own position (blend 1).
window.pmzGeomorphCheck = (T) => {
  const mesh = current.mesh, streamed = mesh.geometry;
  const pos = streamed.getAttribute('position').array, glide = streamed.getAttribute('pmzMorph').array;
  const nv = current.stream.vertexCount, duration = morphClock.uniforms.pmzDuration.value;
  const blended = new Float32Array(3 * nv);
  const counts = { parent: 0, between: 0, own: 0 };
  for (let v = 0; v < nv; ++v) {
    const t = Math.min(1, Math.max(0, (T - glide[4 * v + 3]) / duration));
    if (t === 0) ++counts.parent; else if (t === 1) ++counts.own; else ++counts.between;
    for (let k = 0; k < 3; ++k) blended[3 * v + k] = glide[4 * v + k] * (1 - t) + pos[3 * v + k] * t;
  }
  morphTime = T;
  morphClock.uniforms.pmzTime.value = T;
  mesh.material = material;
  renderer.render(scene, camera);
  const shader = snapshot();
  const fresh = new THREE.BufferGeometry();
  fresh.setAttribute('position', new THREE.BufferAttribute(blended, 3));
  fresh.setIndex(new THREE.BufferAttribute(streamed.getIndex().array.slice(0, streamed.drawRange.count), 1));
  mesh.geometry = fresh;
  mesh.material = plainMaterial;
  renderer.render(scene, camera);
  const cpu = snapshot();
  mesh.geometry = streamed;
  mesh.material = morph.checked ? material : plainMaterial;
  morphTime = null;
  fresh.dispose();
  return { shader, cpu, counts };
};
// Birth times (pmzMorph.w) of the vertices that glide, sorted: for choosing T above.
window.pmzBirthTimes = () => {
  const glide = current.mesh.geometry.getAttribute('pmzMorph').array;
  const out = [];
  for (let v = 0; v < current.stream.vertexCount; ++v) if (glide[4 * v + 3] > -1e5) out.push(glide[4 * v + 3]);
  return out.sort((a, b) => a - b);
};
// Benchmarks: what drawing the current geometry's first F faces costs, for each F in
// faceCounts: render() then a one-pixel readPixels (waits until the GPU process, SwiftShader in
// headless Chromium, has drawn; Chromium's gl.finish() does not wait), median of `reps` after
// one unmeasured draw; with the geomorph material (morphing) or the plain one.
window.pmzDrawCost = (faceCounts, reps = 5, morphing = true) => {
  const gl = renderer.getContext(), mesh = current.mesh, g = mesh.geometry;
  const pixel = new Uint8Array(4);
  const saved = { count: g.drawRange.count, material: mesh.material };
  mesh.material = morphing ? material : plainMaterial;
  const out = [];
  for (const faces of faceCounts) {
    g.setDrawRange(0, 3 * Math.min(faces, current.stream.faceCount));
    const times = [];
    for (let i = 0; i <= reps; ++i) {
      const t0 = performance.now();
      renderer.render(scene, camera);
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel);
      if (i > 0) times.push(performance.now() - t0);
    }
    times.sort((a, b) => a - b);
    out.push({ faces: g.drawRange.count / 3, ms: +times[times.length >> 1].toFixed(2),
      min: +times[0].toFixed(2), max: +times[times.length - 1].toFixed(2) });
  }
  g.setDrawRange(0, saved.count);
  mesh.material = saved.material;
  redraw = true;
  return out;
};

if (params.get('src')) {
  document.getElementById('url').value = params.get('src');
  open(params.get('src'));
}
document.getElementById('open').onclick = () => open(document.getElementById('url').value);
document.getElementById('file').onchange = (e) => e.target.files[0] && open(e.target.files[0]);
const drop = document.getElementById('drop');
window.addEventListener('dragover', (e) => { e.preventDefault(); drop.style.display = 'flex'; });
window.addEventListener('dragleave', () => { drop.style.display = 'none'; });
window.addEventListener('drop', (e) => {
  e.preventDefault();
  drop.style.display = 'none';
  if (e.dataTransfer.files[0]) open(e.dataTransfer.files[0]);
});
