// SPDX-License-Identifier: MIT
// Shared by the web tests: the packed package installed into an empty folder (the contract:
// `npm install ./web/dist/pmz-decoder-*.tgz`, then `import ... from 'pmz-decoder'`), the native
// tools, and the sample streams.
import { execFileSync } from 'node:child_process';
import { existsSync, mkdtempSync, readdirSync, readFileSync, symlinkSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';
import zlib from 'node:zlib';

export const webDir = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '..');
export const rootDir = path.resolve(webDir, '..');
export const binDir = process.env.PMZ_BIN || path.join(rootDir, 'build', 'bin');

let installed = null, installedThree = null;
// The package as a consumer gets it: installed from the tarball, imported by name.
export async function importPackage() {
  if (!installed) {
    const dist = path.join(webDir, 'dist');
    const tgz = readdirSync(dist).find((f) => /^pmz-decoder-.*\.tgz$/.test(f));
    if (!tgz) throw new Error('no web/dist/pmz-decoder-*.tgz: run bash scripts/web.sh');
    const dir = mkdtempSync(path.join(tmpdir(), 'pmz-web-'));
    writeFileSync(path.join(dir, 'package.json'), '{"private": true}\n');
    execFileSync('npm', ['install', '--offline', '--no-audit', '--no-fund', '--loglevel=error',
      path.join(dist, tgz)], { cwd: dir, stdio: ['ignore', 'ignore', 'inherit'] });
    // three (the loader's peer dependency) from web/'s devDependencies.
    symlinkSync(path.join(webDir, 'node_modules', 'three'), path.join(dir, 'node_modules', 'three'));
    writeFileSync(path.join(dir, 'probe.mjs'), "export * from 'pmz-decoder';\n");
    writeFileSync(path.join(dir, 'probe_three.mjs'), "export * from 'pmz-decoder/three';\n");
    installed = import(pathToFileURL(path.join(dir, 'probe.mjs')).href);
    installedThree = import(pathToFileURL(path.join(dir, 'probe_three.mjs')).href);
  }
  return installed;
}

// pmz-decoder/three from the same installation.
export async function importThreeLoader() {
  await importPackage();
  return installedThree;
}

// The procedural sample (pmz-demo: ~50k faces), made once by scripts/web.sh.
export function demoPmz() {
  return process.env.PMZ_WEB_SAMPLE || path.join(webDir, 'build', 'demo', 'sample.pmz');
}

// The native decoder's mesh: pmz-decode's binary little-endian PLY (float xyz, uchar-int lists).
export function nativeDecode(file, extraArgs = []) {
  const out = path.join(mkdtempSync(path.join(tmpdir(), 'pmz-native-')), 'out.ply');
  execFileSync(path.join(binDir, 'pmz-decode'), [file, '-o', out, ...extraArgs],
    { stdio: ['ignore', 'ignore', 'pipe'] });
  const b = readFileSync(out);
  const end = b.indexOf('end_header\n') + 'end_header\n'.length;
  const header = b.subarray(0, end).toString('latin1');
  const nv = Number(/element vertex (\d+)/.exec(header)[1]);
  const nf = Number(/element face (\d+)/.exec(header)[1]);
  const positions = new Float32Array(b.buffer.slice(b.byteOffset + end, b.byteOffset + end + 12 * nv));
  const indices = new Uint32Array(3 * nf);
  const dv = new DataView(b.buffer, b.byteOffset + end + 12 * nv, 13 * nf);
  for (let f = 0; f < nf; ++f) {
    if (dv.getUint8(13 * f) !== 3) throw new Error('pmz-decode wrote a non-triangle');
    for (let k = 0; k < 3; ++k) indices[3 * f + k] = dv.getUint32(13 * f + 1 + 4 * k, true);
  }
  return { positions, indices };
}

// Bitwise equality of two typed arrays (floats compared as their bits).
export function sameBits(a, b) {
  if (a.length !== b.length || a.BYTES_PER_ELEMENT !== b.BYTES_PER_ELEMENT) return false;
  const x = new Uint8Array(a.buffer, a.byteOffset, a.byteLength);
  const y = new Uint8Array(b.buffer, b.byteOffset, b.byteLength);
  return Buffer.compare(x, y) === 0;
}

// The native decoder's arrays through the C API (tests/web/pmz_dump_arrays.c), whole file or at
// a face target: {header (counts, materials), arrays: {name: Uint8Array}}.
export function nativeArrays(file, faces) {
  const out = execFileSync(path.join(binDir, 'pmz-dump-arrays'),
    faces === undefined ? [file] : [file, String(faces)],
    { stdio: ['ignore', 'pipe', 'pipe'], maxBuffer: 1 << 30 });
  const eol = out.indexOf(10);
  const header = JSON.parse(out.subarray(0, eol).toString('utf8'));
  const arrays = {};
  let at = eol + 1;
  for (const [name, bytes] of header.arrays) {
    arrays[name] = new Uint8Array(out.buffer, out.byteOffset + at, bytes);
    at += bytes;
  }
  if (at !== out.length) throw new Error(`pmz-dump-arrays ${file}: ${out.length - at} bytes left`);
  return { header, arrays };
}

// Encodes a mesh file with the native encoder (pmz-encode, default options).
export function encodeNative(input, output) {
  execFileSync(path.join(binDir, 'pmz-encode'), [input, '-o', output],
    { stdio: ['ignore', 'ignore', 'inherit'] });
  return output;
}

// 8-bit RGB PNG (filter 0 rows), for test textures.
export function pngBytes(width, height, pixel) {
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; ++k) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (b) => {
    let c = 0xffffffff;
    for (const x of b) c = crcTable[(c ^ x) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, body) => {
    const b = Buffer.alloc(12 + body.length);
    b.writeUInt32BE(body.length, 0);
    b.write(type, 4, 'latin1');
    body.copy(b, 8);
    b.writeUInt32BE(crc(b.subarray(4, 8 + body.length)), 8 + body.length);
    return b;
  };
  const raw = Buffer.alloc(height * (1 + 3 * width));
  for (let y = 0; y < height; ++y)
    for (let x = 0; x < width; ++x) raw.set(pixel(x, y), y * (1 + 3 * width) + 1 + 3 * x);
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0);
  ihdr.writeUInt32BE(height, 4);
  ihdr.set([8, 2, 0, 0, 0], 8);
  return Buffer.concat([Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk('IHDR', ihdr), chunk('IDAT', zlib.deflateSync(raw)), chunk('IEND', Buffer.alloc(0))]);
}

// The two colours of checker.png (tests/viewer/viewer_test.py's textured torus, same colours).
export const CHECKER_RED = [230, 40, 30], CHECKER_BLUE = [30, 60, 230];

// A rippled torus with texture coordinates wrapping in u and v (a seam: the vertices there get
// two wedges), an MTL naming `texture` with base colour `kd`, and a red / blue checkerboard PNG
// (checker.png): textured.obj in dir.
export function writeTexturedTorus(dir, { texture = 'checker.png', rings = 96, segments = 48, kd = '1 1 1' } = {}) {
  const point = (a, b) => {
    const r = 0.35 * (1 + 0.18 * Math.sin(5 * a) * Math.cos(3 * b));
    return [(1 + r * Math.cos(b)) * Math.cos(a), r * Math.sin(b), (1 + r * Math.cos(b)) * Math.sin(a)];
  };
  const lines = ['mtllib textured.mtl', 'usemtl checker'];
  for (let i = 0; i < rings; ++i)
    for (let j = 0; j < segments; ++j)
      lines.push('v ' + point(2 * Math.PI * i / rings, 2 * Math.PI * j / segments).map((x) => x.toFixed(6)).join(' '));
  for (let i = 0; i <= rings; ++i)
    for (let j = 0; j <= segments; ++j)
      lines.push(`vt ${(4 * i / rings).toFixed(6)} ${(2 * j / segments).toFixed(6)}`);
  for (let i = 0; i < rings; ++i) {
    for (let j = 0; j < segments; ++j) {
      const corners = [[i, j], [i, j + 1], [i + 1, j + 1], [i + 1, j]];
      const v = corners.map(([a, b]) => 1 + (a % rings) * segments + (b % segments));
      const t = corners.map(([a, b]) => 1 + a * (segments + 1) + b);
      lines.push(`f ${v[0]}/${t[0]} ${v[1]}/${t[1]} ${v[2]}/${t[2]}`);
      lines.push(`f ${v[0]}/${t[0]} ${v[2]}/${t[2]} ${v[3]}/${t[3]}`);
    }
  }
  writeFileSync(path.join(dir, 'textured.obj'), lines.join('\n') + '\n');
  writeFileSync(path.join(dir, 'textured.mtl'), `newmtl checker\nKd ${kd}\nmap_Kd ${texture}\n`);
  writeFileSync(path.join(dir, 'checker.png'),
    pngBytes(64, 64, (x, y) => ((x >> 3) + (y >> 3)) % 2 ? CHECKER_RED : CHECKER_BLUE));
  return path.join(dir, 'textured.obj');
}

// A flat 4 x 1 rectangle whose texture coordinates run far outside [0, 1] (u from -7.6 to 8.5,
// v from -1.3 to 2.7: the texture tiles 16 times across and 4 times up it), with a 64-pixel
// red / blue checkerboard of 2 x 2 squares (tiles.png): a square every half unit of u and v,
// 32 across. tiled.obj in dir.
export const TILED_U = [-7.6, 8.5];
export function writeTiledPlane(dir, { columns = 48, rows = 12 } = {}) {
  const lines = ['mtllib tiled.mtl', 'usemtl tiles'];
  for (let j = 0; j <= rows; ++j)
    for (let i = 0; i <= columns; ++i) {
      lines.push(`v ${(4 * i / columns - 2).toFixed(6)} ${(j / rows - 0.5).toFixed(6)} 0`);
      const u = TILED_U[0] + (TILED_U[1] - TILED_U[0]) * i / columns, v = -1.3 + 4 * j / rows;
      lines.push(`vt ${u.toFixed(6)} ${v.toFixed(6)}`);
    }
  const at = (i, j) => 1 + j * (columns + 1) + i;
  for (let j = 0; j < rows; ++j)
    for (let i = 0; i < columns; ++i) {
      const [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
      lines.push(`f ${a}/${a} ${b}/${b} ${c}/${c}`, `f ${a}/${a} ${c}/${c} ${d}/${d}`);
    }
  writeFileSync(path.join(dir, 'tiled.obj'), lines.join('\n') + '\n');
  writeFileSync(path.join(dir, 'tiled.mtl'), 'newmtl tiles\nKd 1 1 1\nmap_Kd tiles.png\n');
  writeFileSync(path.join(dir, 'tiles.png'),
    pngBytes(64, 64, (x, y) => ((x >> 5) + (y >> 5)) % 2 ? CHECKER_RED : CHECKER_BLUE));
  return path.join(dir, 'tiled.obj');
}

// A textured asset of Debian's assimp-testmodels (scripts/fetch_assimp_models.sh puts them in
// corpus-assimp/), or null when they are not there.
export function assimpTextured() {
  const file = path.join(rootDir, 'corpus-assimp', 'OBJ', 'spider.obj');
  return existsSync(file) ? file : null;
}

// A closed torus with ripples (tests/viewer/viewer_test.py's bumpy torus), positions only, as an
// OFF: rings * segments * 2 faces.
export function writeBumpyTorus(dir, { rings = 192, segments = 96 } = {}) {
  const lines = [];
  for (let i = 0; i < rings; ++i) {
    for (let j = 0; j < segments; ++j) {
      const u = 2 * Math.PI * i / rings, v = 2 * Math.PI * j / segments;
      const r = 0.35 * (1 + 0.18 * Math.sin(5 * u) * Math.cos(3 * v));
      const p = [(1 + r * Math.cos(v)) * Math.cos(u), r * Math.sin(v), (1 + r * Math.cos(v)) * Math.sin(u)];
      lines.push(p.map((x) => x.toFixed(6)).join(' '));
    }
  }
  for (let i = 0; i < rings; ++i) {
    for (let j = 0; j < segments; ++j) {
      const v = (a, b) => (a % rings) * segments + (b % segments);
      lines.push(`3 ${v(i, j)} ${v(i, j + 1)} ${v(i + 1, j + 1)}`, `3 ${v(i, j)} ${v(i + 1, j + 1)} ${v(i + 1, j)}`);
    }
  }
  const file = path.join(dir, 'torus.off');
  writeFileSync(file, [`OFF`, `${rings * segments} ${2 * rings * segments} 0`, ...lines].join('\n') + '\n');
  return file;
}

// The same torus as an ASCII PLY with a normal and an RGB colour per vertex (colours varying
// smoothly around it): colours and normals through the stream.
export function writeColoredTorus(dir, { rings = 64, segments = 32 } = {}) {
  const lines = [];
  for (let i = 0; i < rings; ++i) {
    for (let j = 0; j < segments; ++j) {
      const a = 2 * Math.PI * i / rings, b = 2 * Math.PI * j / segments;
      const p = [(1 + 0.35 * Math.cos(b)) * Math.cos(a), 0.35 * Math.sin(b), (1 + 0.35 * Math.cos(b)) * Math.sin(a)];
      const n = [Math.cos(b) * Math.cos(a), Math.sin(b), Math.cos(b) * Math.sin(a)];
      const c = [128 + 100 * Math.cos(a), 128 + 100 * Math.sin(a), 128 + 100 * Math.cos(b)].map(Math.round);
      lines.push([...p, ...n].map((x) => x.toFixed(6)).join(' ') + ' ' + c.join(' '));
    }
  }
  for (let i = 0; i < rings; ++i) {
    for (let j = 0; j < segments; ++j) {
      const v = (a, b) => (a % rings) * segments + (b % segments);
      lines.push(`3 ${v(i, j)} ${v(i, j + 1)} ${v(i + 1, j + 1)}`, `3 ${v(i, j)} ${v(i + 1, j + 1)} ${v(i + 1, j)}`);
    }
  }
  const header = ['ply', 'format ascii 1.0', `element vertex ${rings * segments}`,
    ...['x', 'y', 'z', 'nx', 'ny', 'nz'].map((p) => `property float ${p}`),
    ...['red', 'green', 'blue'].map((p) => `property uchar ${p}`),
    `element face ${2 * rings * segments}`, 'property list uchar int vertex_indices', 'end_header'];
  const file = path.join(dir, 'colored.ply');
  writeFileSync(file, header.concat(lines).join('\n') + '\n');
  return file;
}
