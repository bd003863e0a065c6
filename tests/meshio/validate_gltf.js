// SPDX-License-Identifier: MIT
// Validates a glTF file with the Khronos validator; prints "errors N warnings N" and every
// error, exits 1 on errors. Usage: node validate_gltf.js VALIDATOR_DIR FILE
const fs = require('fs');
const path = require('path');
const validator = require(path.join(process.argv[2], 'node_modules', 'gltf-validator'));
const file = process.argv[3];
const bytes = new Uint8Array(fs.readFileSync(file));
validator.validateBytes(bytes, {
  uri: path.basename(file),
  externalResourceFunction: (uri) => new Promise((resolve, reject) => {
    fs.readFile(path.join(path.dirname(file), decodeURIComponent(uri)),
                (err, data) => err ? reject(err.toString()) : resolve(new Uint8Array(data)));
  }),
}).then((report) => {
  const issues = report.issues;
  console.log(`errors ${issues.numErrors} warnings ${issues.numWarnings}`);
  for (const m of issues.messages) console.log(`${m.severity} ${m.code} ${m.pointer || ''} ${m.message}`);
  process.exit(issues.numErrors ? 1 : 0);
}, (error) => {
  console.log(`validator failed: ${error}`);
  process.exit(1);
});
