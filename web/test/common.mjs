// Shared by the web tests: the packed package installed into an empty folder (the contract:
// `npm install ./web/dist/pmz-decoder-*.tgz`, then `import ... from 'pmz-decoder'`), the native
// tools, and the sample streams.
import { execFileSync } from 'node:child_process';
import { mkdtempSync, readdirSync, readFileSync, symlinkSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import path from 'node:path';
import { fileURLToPath, pathToFileURL } from 'node:url';

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
