#!/usr/bin/env node
// Runs the Khronos glTF-Validator on one .glb/.gltf file.
//
//   node validate_gltf.mjs FILE [--max-issues N] [--json]
//
// The validator is the npm package that scripts/setup installs into .tools/npm; the
// environment variable KODAWARI_NODE_TOOLS points elsewhere (a folder holding
// node_modules/gltf-validator). Exit status: 0 no errors, 1 errors, 2 usage or I/O.
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';

const usage = 'usage: node validate_gltf.mjs FILE.glb [--max-issues N] [--json]';

function fail(message) {
  console.error(`validate_gltf: ${message}`);
  process.exit(2);
}

let file = null;
let maxIssues = 0; // the validator's "no limit"
let json = false;
const args = process.argv.slice(2);
for (let i = 0; i < args.length; ++i) {
  const arg = args[i];
  if (arg === '--json') {
    json = true;
  } else if (arg === '--max-issues') {
    const value = Number(args[++i]);
    if (!Number.isInteger(value) || value < 0) fail(`--max-issues needs a count\n${usage}`);
    maxIssues = value;
  } else if (arg === '-h' || arg === '--help') {
    console.log(usage);
    process.exit(0);
  } else if (arg.startsWith('-')) {
    fail(`unknown option ${arg}\n${usage}`);
  } else if (file === null) {
    file = arg;
  } else {
    fail(`more than one file given\n${usage}`);
  }
}
if (file === null) fail(usage);

const here = path.dirname(fileURLToPath(import.meta.url));
const tools = process.env.KODAWARI_NODE_TOOLS || path.resolve(here, '..', '..', '.tools', 'npm');
const require = createRequire(path.join(tools, 'package.json'));
let validator;
try {
  validator = require(path.join(tools, 'node_modules', 'gltf-validator'));
} catch (error) {
  fail(`cannot load gltf-validator from ${tools}/node_modules (run scripts/setup): ${error.message}`);
}

let bytes;
try {
  bytes = new Uint8Array(readFileSync(file));
} catch (error) {
  fail(`${file}: ${error.message}`);
}

let report;
try {
  report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues,
    // A .glb from the simulator is self-contained; anything external is a defect.
    externalResourceFunction: (uri) => Promise.reject(new Error(`external resource ${uri} not allowed`)),
  });
} catch (error) {
  fail(`${file}: validator failed: ${error && error.message ? error.message : error}`);
}

const issues = report.issues;
console.log(
  `glTF-Validator: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
    `${issues.numInfos} infos, ${issues.numHints} hints`,
);
const severityNames = ['error', 'warning'];
for (const message of issues.messages) {
  if (message.severity > 1) continue;
  const where = message.pointer ? ` at ${message.pointer}` : message.offset !== undefined ? ` at byte ${message.offset}` : '';
  console.log(`  ${severityNames[message.severity]} ${message.code}${where}: ${message.message}`);
}
if (json) {
  console.log('--- report ---');
  console.log(JSON.stringify(report, null, 2));
}
process.exit(issues.numErrors === 0 ? 0 : 1);
