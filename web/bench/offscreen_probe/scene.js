// SPDX-License-Identifier: MIT
// A grid of about `faces` triangles drawn as the viewer draws a stream (MeshStandardMaterial,
// flat shading, double sided, no MSAA, one pixel per CSS pixel), swaying so each frame differs.
// Returns draw(t). The scene and grid repeat render.js's (camera, lights; its calibration grid)
// on purpose: the probe measures the same drawing without the viewer, and stands alone.
export function makeScene(THREE, canvas, width, height, faces) {
  const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
  renderer.setPixelRatio(1);
  renderer.setSize(width, height, false);
  renderer.setClearColor(0x20242a);
  const scene = new THREE.Scene();
  const camera = new THREE.PerspectiveCamera(40, width / height, 0.01, 100);
  camera.position.set(0, 0, 3);
  scene.add(camera);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x404050, 1.2));
  const light = new THREE.DirectionalLight(0xffffff, 2.0);
  light.position.set(1, 1.5, 2);
  camera.add(light);
  const n = Math.ceil(Math.sqrt(faces / 2)), positions = new Float32Array(3 * (n + 1) * (n + 1));
  for (let i = 0, k = 0; i <= n; ++i)
    for (let j = 0; j <= n; ++j, k += 3) positions.set([(j / n - 0.5) * 1.2, (i / n - 0.5) * 1.2, 0.1 * Math.sin(i * 0.3 + j * 0.2)], k);
  const index = new Uint32Array(6 * n * n);
  for (let i = 0, k = 0; i < n; ++i)
    for (let j = 0; j < n; ++j, k += 6) {
      const a = i * (n + 1) + j, b = a + n + 1;
      index.set([a, a + 1, b, a + 1, b + 1, b], k);
    }
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.BufferAttribute(positions, 3));
  g.setIndex(new THREE.BufferAttribute(index, 1));
  const mesh = new THREE.Mesh(g, new THREE.MeshStandardMaterial({ color: 0xd8c8a8, flatShading: true,
    side: THREE.DoubleSide }));
  scene.add(mesh);
  return (t) => {
    mesh.rotation.y = 0.3 * Math.sin(t / 1000);
    renderer.render(scene, camera);
  };
}
