// SPDX-License-Identifier: MIT
// pmz web viewer, the drawing side: the scene, the stream (PMZLoader) and the frame loop. Runs in
// a Web Worker on an OffscreenCanvas (render_worker.js; the default where workers have WebGL2) or
// on the page's own canvas (viewer.js's fallback), driven by the same messages either way: the
// page (viewer.js) forwards input and shows the overlay; this side posts the stream's state.
//
// Messages in:  {type: 'open', source} (absolute URL or Blob/File) | {type: 'camera', position,
//               quaternion} | {type: 'resize', width, height} | {type: 'faces', faces} (LOD
//               target, null: follow the stream) | {type: 'morph', on} | {type: 'call', id,
//               name, args} (test and benchmark hooks: see CALLS)
// Messages out: {type: 'state', status, info, overlay, timing, attributes, calibration} when
//               something changed | {type: 'fit', position, target} (the camera framing a new
//               stream) | {type: 'reply', id, result, error} | {type: 'warn', text}
// Times posted are this thread's performance.now(); the page adds the clocks' offset.
import * as THREE from './vendor/three.module.js';
import { createDecoder } from './pmz/index.js';
import { PMZLoader, geomorphMaterial, pmzMaterials } from './pmz/three.js';

const REFINE_BUDGET_MS = 8;  // ?worker=0: refinement per frame on this thread
const BACKGROUND = 0x20242a;

// MSAA about doubles a frame's cost in a software renderer (SwiftShader, 75k-face bunny at load
// 15: median frame gap 283 ms with, 117 ms without): off there, on elsewhere; ?aa=0/1 decides.
function softwareRenderer() {
  try {
    const canvas = typeof OffscreenCanvas === 'function' ? new OffscreenCanvas(1, 1) : document.createElement('canvas');
    const gl = canvas.getContext('webgl2');
    const info = gl && gl.getExtension('WEBGL_debug_renderer_info');
    const name = info ? String(gl.getParameter(info.UNMASKED_RENDERER_WEBGL)) : '';
    const lose = gl && gl.getExtension('WEBGL_lose_context');
    if (lose) lose.loseContext();
    return /swiftshader|llvmpipe|softpipe|software/i.test(name);
  } catch (e) {
    return false;
  }
}

// Textures where the DOM's image loading (TextureLoader) is missing, in a worker: decoded to an
// ImageBitmap, flipped as TextureLoader's textures are (flipY does not apply to bitmaps).
function bitmapTextureLoader() {
  const loader = new THREE.ImageBitmapLoader();
  loader.setOptions({ imageOrientation: 'flipY' });
  return {
    load(url, onLoad, onProgress, onError) {
      const texture = new THREE.Texture();
      texture.flipY = false;
      loader.load(url, (bitmap) => {
        texture.image = bitmap;
        texture.needsUpdate = true;
        if (onLoad) onLoad(texture);
      }, onProgress, onError);
      return texture;
    },
  };
}

// Whether the stream at url has a node table (and no attributes) and its server answers Range:
// its header, from the first PROBE_BYTES bytes asked for by a range (a plain stream's header
// is about 50 bytes). Such a stream is decoded for the camera (PMZViewStream); any other, or any
// failure here, is streamed in order as before.
const PROBE_BYTES = 256;
async function viewDecodable(url) {
  let d = null;
  try {
    const r = await fetch(url, { headers: { Range: `bytes=0-${PROBE_BYTES - 1}` } });
    const bytes = new Uint8Array(await r.arrayBuffer());
    if (r.status !== 206 || bytes.length > PROBE_BYTES) return false;
    d = await createDecoder({ workers: 1 });
    d.feed(bytes);
    const info = d.info();
    return info.headerDone && (info.flags & 2) !== 0 && (info.flags & 1) === 0;
  } catch (e) {
    return false;
  } finally {
    if (d) d.dispose();
  }
}

// canvas: an OffscreenCanvas (worker) or the page's canvas; width, height in CSS pixels;
// query: the page's URL parameters (a string); post(message): to the page.
export function createView({ canvas, width, height, pixelRatio, query, post }) {
  const params = new URLSearchParams(query);
  const useWorker = params.get('worker') !== '0' && typeof Worker === 'function';
  // ?workers=N: the decoder's threads (createDecoder's workers; default the cores, where the
  // page is cross-origin isolated).
  const workers = Number(params.get('workers')) >= 1 ? Math.floor(Number(params.get('workers'))) : undefined;
  // View-dependent decoding of streams with a node table (?view=0: streamed in order as others):
  // ?camera=EX,EY,EZ,TX,TY,TZ (the mesh's coordinates) the first camera, ?pixelerror=P;
  // ?maxfaces=N (MAX_FACES below) is their face budget (PMZViewStream.maxFaces).
  const viewDecoding = params.get('view') !== '0';
  const pixelError = Number(params.get('pixelerror')) > 0 ? Number(params.get('pixelerror')) : 1;
  const cameraParam = (params.get('camera') || '').split(',').map(Number);
  const startCamera = cameraParam.length === 6 && cameraParam.every(Number.isFinite) ? cameraParam : null;
  const software = softwareRenderer();
  const antialias = params.has('aa') ? params.get('aa') !== '0' : !software;
  const renderer = new THREE.WebGLRenderer({ canvas, antialias, preserveDrawingBuffer: true });
  // A software renderer shades every device pixel on the CPU: CSS pixels there.
  renderer.setPixelRatio(software ? 1 : pixelRatio);
  renderer.setSize(width, height, false);
  renderer.setClearColor(BACKGROUND);
  // Under a software renderer (SwiftShader in headless Chromium) the canvas's backing store is
  // at DECODE_SCALE of its size while a stream decodes (?decodescale=F in (0, 1], default 0.5;
  // 1: always full size), full size again from the first frame drawn once decoding ended
  // (complete, or failed and what arrived before the damage shown). There the display
  // compositor waits for each drawn canvas frame before it sends the page's next frame (a
  // Chromium trace shows it), and a canvas frame costs per pixel too (shading, read-back,
  // software compositing): at half the width and height the page's longest gap while decoding
  // was within 50 ms in 25 of 27 runs at load 1.3-9, against 16 of 27 at full size
  // (docs/benchmarks.md, "Web viewer frames"). The faces shown still rise; the
  // object is drawn at full resolution once complete. (Drawing on the page, render=page, it did
  // not help.)
  const askedScale = Number(params.get('decodescale'));  // 0 when absent, NaN when not a number
  const DECODE_SCALE = !software ? 1 : askedScale > 0 && askedScale <= 1 ? askedScale : 0.5;
  const cssSize = { width, height };
  let scaledDown = false;
  function scaleForDecoding(on) {
    if (on === scaledDown) return;
    scaledDown = on;
    renderer.setPixelRatio((software ? 1 : pixelRatio) * (on ? DECODE_SCALE : 1));
    renderer.setSize(cssSize.width, cssSize.height, false);
  }
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(40, width / height, 0.01, 100);
  camera.position.set(0, 0, 3);
  scene.add(camera);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.2));
  const light = new THREE.DirectionalLight(0xffffff, 2.0);
  light.position.set(1, 1.5, 2);
  camera.add(light);
  // Frames are drawn when something changed (geometry, view, material, a texture arrived, new
  // vertices still gliding): redrawing an unchanged scene only takes CPU from the decoder, and
  // a software renderer needs a good part of a second for a large mesh on a loaded machine.
  let redraw = true, glideUntil = 0;
  const requestRedraw = () => { redraw = true; };
  let morphOn = true;

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
  // DRAW_BUDGET_MS (of the 50 ms a frame may take: the rest is the frame's own work and its
  // alignment); the finest level is shown once decoding ends (PMZStream.faceLimit).
  // The cost per face starts from a calibration draw before the stream opens and follows the
  // frames' timestamps. The calibration draws while nothing decodes: during the stream the
  // decoding worker takes a core SwiftShader would otherwise use, and faces once shown cannot be
  // taken back while decoding. So the shown faces grow in steps frames have proven: at most
  // GROWTH x the most faces a frame drew within DRAW_BUDGET_MS (at least GROWTH_START_FACES).
  // A frame that took longer than SLOW_FRAME_MS after drawing F >= MIN_SAMPLE_FACES faces is a
  // sample gap / F (the median of the last five is the estimate), a faster one bounds the cost
  // by gap / F. A machine too busy to keep even the frames that draw nothing at the display's
  // rate is not drawing's doing: what their gaps (median of the last nine) exceed a vsync by is
  // taken off the drawn frames' gaps first. ?maxfaces=N caps the faces shown while decoding.
  const DRAW_BUDGET_MS = params.has('drawms') ? Number(params.get('drawms')) : 30;
  const MAX_FACES = params.has('maxfaces') ? Number(params.get('maxfaces')) : Infinity;
  const maxFaces = MAX_FACES > 0 && MAX_FACES < Infinity ? Math.floor(MAX_FACES) : 0;  // (0: none)
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

  // ?gputime=1 (benchmarks): each drawn frame gets gpu, the ms from its render() to when a fence
  // after its commands was seen signalled (polled every few ms): how long the GPU process (the
  // compositor's wait included) took to run it. No EXT_disjoint_timer_query in SwiftShader.
  const GPU_TIME = params.get('gputime') === '1';
  const gl2 = renderer.getContext();
  let inFlight = null;  // {sync, t, frame}
  function pollFence() {
    if (gl2.getSyncParameter(inFlight.sync, gl2.SYNC_STATUS) !== gl2.SIGNALED) {
      setTimeout(pollFence, 2);
      return;
    }
    if (inFlight.frame) inFlight.frame.gpu = performance.now() - inFlight.t;
    gl2.deleteSync(inFlight.sync);
    inFlight = null;
  }

  // The face limit for the stream now (null: none).
  function faceLimit(shownFaces, fullFaces) {
    let limit = MAX_FACES;
    if (DRAW_BUDGET_MS > 0 && drawCost.perFace > 0) {
      const proven = GROWTH > 0 ? GROWTH * Math.max(drawCost.proven, GROWTH_START_FACES / GROWTH) : Infinity;
      limit = Math.min(limit, Math.max(shownFaces, Math.floor(Math.min(proven, DRAW_BUDGET_MS / drawCost.perFace))));
    }
    return limit >= fullFaces ? null : limit;
  }

  let calibration = null;
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
    calibration = { faces: 2 * n * n, ms };
  }

  // The stream's state for the page (pmzStatus, the overlay), timings (this thread's
  // performance.now() ms) and one entry per animation frame here (the canvas's frames). ended:
  // decoding ended (complete, or failed: a stream that failed shows what arrived before the
  // damage, the error beside it; PMZStream.ended).
  const status = { faces: 0, vertices: 0, bytes: 0, totalBytes: 0, complete: false, ended: false, error: '' };
  let timing = { firstBytes: null, firstObjectFrame: null };
  let frames = [];
  let attributes = null;  // tests: the attributes the geometry draws with, and how many materials
  let posted = '';  // the last state posted (JSON), to post only changes

  // Streams with attributes (texture coordinates, normals, colours, materials) are drawn with
  // pmzMaterials(): textured, lit with their normals; each with a geomorph twin.
  let morphTicks = [];  // geomorph clocks of the dressed materials
  // Until its texture arrives a material draws its base colour (pmzMaterials: a white texel
  // as its map); the texture then goes to its geomorph twin too.
  function dress(stream) {
    const twins = new Map();
    const plain = pmzMaterials(stream, {
      onTextureLoad: (texture, m) => {
        if (twins.has(m)) twins.get(m).map = texture;
        requestRedraw();
      },
      onTextureError: (url) => post({ type: 'warn', text: `pmz viewer: texture ${url} not loaded; drawn untextured` }),
      textureLoader: typeof document === 'undefined' ? bitmapTextureLoader() : undefined,
    });
    const morphing = plain.map((m) => {
      const twin = m.clone();
      twins.set(m, twin);
      morphTicks.push(geomorphMaterial(twin, GLIDE_SECONDS));
      return twin;
    });
    const one = (a) => (a.length === 1 ? a[0] : a);  // an array draws only the geometry's groups
    return { plain: one(plain), morph: one(morphing) };
  }

  // Compiles the programs of materials ({plain, morph}, each one or an array) for a geometry,
  // in parallel where the browser can (KHR_parallel_shader_compile), lit as the scene is.
  function compileFirst(materials, geometry) {
    const probe = new THREE.Group();
    for (const m of [materials.plain, materials.morph].flat()) probe.add(new THREE.Mesh(geometry, m));
    return renderer.compileAsync(probe, camera, scene).catch((e) => post({ type: 'warn', text: `pmz viewer: ${e}` }));
  }

  let current = null;  // { stream, mesh, fitted, materials }
  let faceTarget = null;  // null: follow the stream; else the LOD slider's face count
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
    Object.assign(status, { faces: 0, vertices: 0, bytes: 0, totalBytes: 0, complete: false, ended: false, error: '' });
    delete status.nodes;
    delete status.totalNodes;
    delete status.maxFaces;
    timing = { firstBytes: null, firstObjectFrame: null };
    frames = [];
    attributes = null;
    drawCost.proven = 0;
    try {
      await shadersReady;  // and the draw calibration: the first face limit
      // Before the first bytes: resizing the drawing buffer at the first object frame delayed it.
      if (DECODE_SCALE !== 1) scaleForDecoding(true);
      const byView = viewDecoding && typeof source === 'string' && await viewDecodable(source);
      const loader = new PMZLoader(undefined, byView ? { autoUpdate: false, workers, view: { pixelError, maxFaces } }
        : { geomorph: true, autoUpdate: false, worker: useWorker, workers, faceLimit: faceLimit(0, Infinity) });
      const stream = await loader.stream(source, (s) => {
        if (timing.firstBytes === null && s.bytes > 0) timing.firstBytes = performance.now();
        status.bytes = s.bytes;
        status.totalBytes = s.totalBytes;
      });
      const mesh = new THREE.Mesh(stream.geometry, morphOn && !byView ? material : plainMaterial);
      mesh.frustumCulled = false;
      scene.add(mesh);
      redraw = true;
      current = { stream, mesh, fitted: false, materials: null, byView };
      if (byView) {
        stream.object = mesh;
        current.materials = { plain: plainMaterial, morph: plainMaterial };  // (no geomorphs)
      }
      const result = await stream.done;
      if (result !== 'ok') setError(stream.error || result);
    } catch (e) {
      setError(e && e.message ? e.message : e);
      status.ended = true;
    }
  }

  // Frames the stream's bounding box; the page's orbit controls take the view from here.
  function fit(info) {
    const min = new THREE.Vector3(...info.bboxMin), max = new THREE.Vector3(...info.bboxMax);
    const center = min.clone().add(max).multiplyScalar(0.5);
    const radius = Math.max(1e-6, max.distanceTo(min) / 2);
    let distance = radius / Math.sin(THREE.MathUtils.degToRad(camera.fov / 2)) * 1.05;
    let target = center;
    if (startCamera) {  // ?camera=
      camera.position.fromArray(startCamera);
      target = new THREE.Vector3().fromArray(startCamera, 3);
      distance = Math.max(1e-6, camera.position.distanceTo(target));
      camera.near = Math.min(distance, radius) / 100;
      camera.far = (distance + 2 * radius) * 10;
    } else {
      camera.position.copy(center).add(new THREE.Vector3(0.35, 0.3, 1).normalize().multiplyScalar(distance));
      camera.near = distance / 100;
      camera.far = distance * 10;
    }
    camera.lookAt(target);
    camera.updateProjectionMatrix();
    post({ type: 'fit', position: camera.position.toArray(), target: target.toArray(), near: camera.near, far: camera.far });
  }

  function postState(limit) {
    const s = current && current.stream;
    const state = { type: 'state', status, info: s ? s.info() : null, timing, attributes, calibration,
      overlay: s ? { limited: limit !== null && !status.ended, decodedFaces: s.decodedFaces,
        rate: Math.round(rate.perSecond), byView: !!current.byView } : null };
    const text = JSON.stringify(state);
    if (text !== posted) {
      posted = text;
      post(state);
    }
  }

  // Faces drawn (not degenerate: those of nodes not applied are) in a view stream's geometry.
  function drawnFaces(g) {
    const index = g.getIndex(), n = g.drawRange.count;
    if (!index) return 0;
    const a = index.array;
    let faces = 0;
    for (let i = 0; i < n; i += 3) if (a[i] !== a[i + 1]) ++faces;
    return faces;
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
      const t0 = performance.now();
      if (current.byView) {  // the nodes this camera needs, fetched by ranges
        s.viewportHeight = renderer.domElement.height;
        if (s.update(current.fitted ? camera : null, current.mesh, REFINE_BUDGET_MS)) {
          redraw = true;
          current.drawnFaces = drawnFaces(s.geometry);
        }
      } else {
        s.faceTarget = faceTarget;
        s.faceLimit = limit = faceLimit(s.faceCount, info.headerDone ? info.fullFaces : Infinity);
        if (s.update(REFINE_BUDGET_MS)) {
          redraw = true;
          glideUntil = performance.now() + 1000 * GLIDE_SECONDS + 50;
        }
      }
      work = performance.now() - t0;
      const g = s.geometry;
      if (!current.materials && !current.dressing && g.getAttribute('position')) {
        const dressed = ['uv', 'normal', 'color'].some((n) => g.getAttribute(n)) || s.materials().length > 1;
        if (dressed) {
          // The dressed materials' programs are compiled before they draw (the plain ones draw
          // meanwhile): compiling at their first draw blocked the page.
          const materials = dress(s), c = current;
          c.dressing = true;
          compileFirst(materials, g).then(() => {
            c.materials = materials;
            redraw = true;
          });
        } else {
          current.materials = { plain: plainMaterial, morph: material };
        }
        attributes = { names: ['uv', 'uv1', 'normal', 'color'].filter((n) => g.getAttribute(n)),
          materials: s.materials().length };
      }
      rate.splits += Math.max(0, s.splitsApplied - before);
      if (timing.firstBytes === null && s.firstBytesTime != null) timing.firstBytes = s.firstBytesTime;
      Object.assign(status, { bytes: s.bytes, totalBytes: s.totalBytes });
      Object.assign(status, { faces: current.byView ? current.drawnFaces ?? 0 : s.faceCount,
        vertices: s.vertexCount, complete: s.complete, ended: status.ended || s.ended });
      if (current.byView) Object.assign(status, { nodes: s.nodesApplied, totalNodes: s.nodeCount, maxFaces });
      if (s.status !== 'ok' || s.error) setError(s.error);  // (a view stream's failed request too)
      const m = current.materials && (morphOn ? current.materials.morph : current.materials.plain);
      if (m && current.mesh.material !== m) {
        current.mesh.material = m;
        redraw = true;
      }
    }
    if (morphTime === null) {
      morphClock();
      for (const tick of morphTicks) tick();
    }
    const t0r = performance.now();
    // Gliding vertices redraw every frame, up to the first frame past the glide's end (frames
    // can be far apart: stopping at the last one before it left the mesh mid-glide on screen).
    const drawn = redraw || (morphOn && glideUntil > 0);
    if (t0r >= glideUntil) glideUntil = 0;
    if (drawn && YIELD_DRAW && current && current.stream.pauseDecoding && status.faces > 0 && !status.complete &&
        t0r >= yieldAgain) {
      const ms = Math.min(40, Math.max(VSYNC_MS, drawCost.lastDrawing || VSYNC_MS));
      current.stream.pauseDecoding(ms);
      yieldAgain = t0r + 2 * ms;
    }
    if (scaledDown && drawn && status.ended) scaleForDecoding(false);
    if (drawn) renderer.render(scene, camera);
    redraw = false;
    const now = performance.now();
    if (drawn && status.faces > 0 && timing.firstObjectFrame === null) {
      timing.firstObjectFrame = now;
      timing.firstObjectFaces = status.faces;
    }
    if (drawn) drawCost.last = { t, faces: status.faces };
    if (frames.length < 100000) {
      frames.push({ t, faces: status.faces, bytes: status.bytes, work, render: now - t0r, drawn,
        limit, decoded: current ? current.stream.decodedFaces : 0, js: 0 });
    }
    if (GPU_TIME && drawn && !inFlight) {
      inFlight = { sync: gl2.fenceSync(gl2.SYNC_GPU_COMMANDS_COMPLETE, 0), t: now,
        frame: frames.length < 100000 ? frames[frames.length - 1] : null };
      gl2.flush();
      setTimeout(pollFence, 2);
    }
    if (now - rate.t >= 500) {
      rate = { t: now, splits: 0, perSecond: rate.splits / ((now - rate.t) / 1000) };
    }
    postState(limit);
    // The whole callback's time (update, render() call, state): this thread's JS per frame.
    if (frames.length) frames[frames.length - 1].js = performance.now() - tStart;
  }
  requestAnimationFrame(frame);

  // Tests: the canvas's coverage (share of pixels not the background) with a downsampled copy
  // for comparing two frames.
  function snapshot() {
    const src = renderer.domElement, w = 200, h = Math.round(200 * src.height / src.width);
    const c = typeof OffscreenCanvas === 'function' ? new OffscreenCanvas(w, h) : document.createElement('canvas');
    c.width = w;
    c.height = h;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0, w, h);
    const px = g.getImageData(0, 0, w, h).data;
    const bg = new THREE.Color(BACKGROUND);
    const br = Math.round(bg.r * 255), bgg = Math.round(bg.g * 255), bb = Math.round(bg.b * 255);
    let covered = 0;
    for (let i = 0; i < px.length; i += 4)
      if (Math.abs(px[i] - br) + Math.abs(px[i + 1] - bgg) + Math.abs(px[i + 2] - bb) > 24) ++covered;
    return { coverage: covered / (w * h), pixels: Array.from(px) };
  }

  // Test and benchmark hooks, called by the page ({type: 'call', name, args}); viewer.js exposes
  // them as window.pmzSnapshot() and so on (each returning a promise).
  const CALLS = {
    snapshot() {
      renderer.render(scene, camera);
      return snapshot();
    },
    // The same view drawn from a geometry built afresh from the decoder's current buffers: what
    // the in-place updated geometry must look like.
    async referenceSnapshot() {
      const d = (await current.stream.snapshot()).render, streamed = current.mesh.geometry;
      const fresh = new THREE.BufferGeometry();
      fresh.setAttribute('position', new THREE.BufferAttribute(d.positions, 3));
      for (const [name, size] of d.layout) fresh.setAttribute(name, new THREE.BufferAttribute(d.attributes[name], size));
      fresh.setIndex(new THREE.BufferAttribute(d.indices, 1));
      for (const group of streamed.groups) fresh.addGroup(group.start, group.count, group.materialIndex);
      const savedMaterial = current.mesh.material;
      current.mesh.geometry = fresh;
      current.mesh.material = current.materials ? current.materials.plain : plainMaterial;
      renderer.render(scene, camera);
      const shot = snapshot();
      current.mesh.geometry = streamed;
      current.mesh.material = savedMaterial;
      fresh.dispose();
      redraw = true;
      return shot;
    },
    // The geomorph shader at time T (seconds) against the same blend computed here from the
    // geometry's pmzMorph attribute and drawn without geomorphs. Returns both snapshots and how
    // many vertices sit at their parent (blend 0), between, and at their own position (blend 1).
    geomorphCheck(T) {
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
      mesh.material = morphOn ? material : plainMaterial;
      morphTime = null;
      fresh.dispose();
      redraw = true;
      return { shader, cpu, counts };
    },
    // Birth times (pmzMorph.w) of the vertices that glide, sorted: for choosing T above. On
    // this thread's clock (seconds), as geomorphCheck takes them.
    birthTimes() {
      const glide = current.mesh.geometry.getAttribute('pmzMorph').array;
      const out = [];
      for (let v = 0; v < current.stream.vertexCount; ++v) if (glide[4 * v + 3] > -1e5) out.push(glide[4 * v + 3]);
      return out.sort((a, b) => a - b);
    },
    // Benchmarks: what drawing the current geometry's first F faces costs, for each F in
    // faceCounts: render() then a one-pixel readPixels (waits until the GPU process, SwiftShader
    // in headless Chromium, has drawn; Chromium's gl.finish() does not wait), median of `reps`
    // after one unmeasured draw; with the geomorph material (morphing) or the plain one.
    drawCost(faceCounts, reps = 5, morphing = true) {
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
      return { rows: out, canvas: [renderer.domElement.width, renderer.domElement.height] };
    },
    // The canvas's frames (see frame()): {t, faces, bytes, work, render, drawn, limit, decoded, js}.
    frames() {
      return frames;
    },
  };

  return {
    handle(m) {
      switch (m.type) {
        case 'open': open(m.source); break;
        case 'camera':
          camera.position.fromArray(m.position);
          camera.quaternion.fromArray(m.quaternion);
          redraw = true;
          break;
        case 'resize':
          camera.aspect = m.width / m.height;
          camera.updateProjectionMatrix();
          Object.assign(cssSize, { width: m.width, height: m.height });
          renderer.setSize(m.width, m.height, false);
          redraw = true;
          break;
        case 'faces': faceTarget = m.faces; break;
        case 'morph': morphOn = m.on; redraw = true; break;
        case 'call':
          Promise.resolve().then(() => CALLS[m.name](...(m.args || []))).then(
            (result) => post({ type: 'reply', id: m.id, result }),
            (e) => post({ type: 'reply', id: m.id, error: String(e && e.message ? e.message : e) }));
          break;
      }
    },
  };
}
