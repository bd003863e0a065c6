// SPDX-License-Identifier: MIT
// Placed before the threaded module's glue (scripts/web.sh: em++ --extern-pre-js): emscripten
// 3.1.6's ES module glue, in node, calls CommonJS's require (fs, path, worker_threads) and reads
// __dirname, which an ES module lacks; these give them. In browsers both stay undefined (the
// glue's browser branch does not use them).
const pmzInNode = typeof process == 'object' && !!(process.versions && process.versions.node);
var require = pmzInNode ? (await import('node:module')).createRequire(import.meta.url) : undefined;
var __dirname = pmzInNode ? require('node:path').dirname(require('node:url').fileURLToPath(import.meta.url))
  : undefined;
