#!/usr/bin/env node
// Keeps docs/scene.schema.json in step with the scene loader (ctest -L schema):
//   1. every shipped scene is valid under the schema and names it first with "$schema";
//   2. every bad scene of tests/schema/cases.json is rejected by the loader (at the JSON
//      path the case names, so it fails for the reason meant) and by the schema, and each
//      case's good variant is accepted by both; the loader rules that JSON Schema cannot
//      state are checked the other way round (loader rejects, schema accepts) and listed;
//   3. `kodawari schema` prints docs/scene.schema.json byte for byte.
//
//   node schema_test.mjs KODAWARI_BINARY SOURCE_DIR
//
// The validator is Ajv (draft 2020-12), which scripts/setup installs into .tools/npm
// (KODAWARI_NODE_TOOLS points elsewhere). Exit status: 0 all passed, 1 a check failed,
// 2 usage or a missing tool.
import { createRequire } from 'node:module';
import { execFileSync, spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, readdirSync, rmSync, symlinkSync, writeFileSync } from 'node:fs';
import os from 'node:os';
import path from 'node:path';

function fail(message) {
  console.error(`schema_test: ${message}`);
  process.exit(2);
}

const [kodawari, sourceDir] = process.argv.slice(2);
if (!kodawari || !sourceDir) fail('usage: node schema_test.mjs KODAWARI_BINARY SOURCE_DIR');
const tools = process.env.KODAWARI_NODE_TOOLS || path.join(sourceDir, '.tools', 'npm');
let Ajv2020;
try {
  Ajv2020 = createRequire(path.join(tools, 'package.json'))('ajv/dist/2020').default;
} catch (error) {
  fail(`cannot load ajv from ${tools}/node_modules (run scripts/setup): ${error.message}`);
}

const schemaPath = path.join(sourceDir, 'docs', 'scene.schema.json');
const schemaBytes = readFileSync(schemaPath);
// strictSchema catches misspelt keywords and numbers that are not JSON's. The style rules
// are off: strictRequired and strictTypes want every if/then fragment to repeat the
// properties and types its parent already states, and strictTuples wants prefixItems to
// describe whole arrays, where a shape's positions fix only joint 0.
const ajv = new Ajv2020({ strict: true, strictRequired: false, strictTypes: false, strictTuples: false, allErrors: true });
let validate;
try {
  validate = ajv.compile(JSON.parse(schemaBytes.toString('utf8')));
} catch (error) {
  console.error(`FAIL: ${schemaPath} is not a valid draft 2020-12 schema: ${error.message}`);
  process.exit(1);
}

let failures = 0;
function check(ok, message) {
  if (!ok) {
    failures += 1;
    console.log(`FAIL: ${message}`);
  }
  return ok;
}
function schemaErrors() {
  return (validate.errors || []).slice(0, 4).map((e) => `${e.instancePath || '/'} ${e.message}`).join('; ');
}

// 1. The shipped scenes. Globbing here is fine: a new scene is picked up without a list.
const sceneDirs = ['scenes', 'scenes/bench', 'scenes/characters'];
let shipped = 0;
for (const dir of sceneDirs) {
  let names = [];
  try {
    names = readdirSync(path.join(sourceDir, dir)).filter((n) => n.endsWith('.json')).sort();
  } catch {
    continue;
  }
  for (const name of names) {
    const file = path.join(dir, name);
    const text = readFileSync(path.join(sourceDir, file), 'utf8');
    const doc = JSON.parse(text);
    shipped += 1;
    check(validate(doc), `${file} is not valid under the schema: ${schemaErrors()}`);
    const reference = path.relative(path.join(sourceDir, dir), schemaPath).split(path.sep).join('/');
    check(Object.keys(doc)[0] === '$schema' && doc.$schema === reference,
      `${file}: the first key should be "$schema": "${reference}", got ${JSON.stringify(Object.keys(doc)[0])}: ${JSON.stringify(doc.$schema)}`);
  }
}
check(shipped > 0, 'no shipped scenes found');
// The scene examples of docs/scene-format.md (its ```json blocks; the loader's test loads them).
const formatDoc = readFileSync(path.join(sourceDir, 'docs', 'scene-format.md'), 'utf8');
let examples = 0;
for (const m of formatDoc.matchAll(/```json\n([\s\S]*?)```/g)) {
  examples += 1;
  check(validate(JSON.parse(m[1])), `docs/scene-format.md example ${examples} is not valid under the schema: ${schemaErrors()}`);
}
check(examples >= 2, `docs/scene-format.md: ${examples} scene examples found, expected at least 2`);
console.log(`shipped scenes: ${shipped}, and ${examples} examples of docs/scene-format.md, valid under the schema`);

// 2. Bad scenes and their good variants.
const cases = JSON.parse(readFileSync(path.join(sourceDir, 'tests', 'schema', 'cases.json'), 'utf8'));
const work = mkdtempSync(path.join(os.tmpdir(), 'kodawari-schema-'));
// Rigged bases name "characters/chibi.glb" relative to the scene, as scenes/crowd-gltf.json.
symlinkSync(path.join(sourceDir, 'scenes', 'characters'), path.join(work, 'characters'));
// Motions' name maps (docs/motions.md) as "motions/chibi-humanoid.json".
symlinkSync(path.join(sourceDir, 'tests', 'assets', 'motion'), path.join(work, 'motions'));

function pointer(p) {
  return p.split('/').slice(1).map((k) => k.replace(/~1/g, '/').replace(/~0/g, '~'));
}
// "@repeat N JSON": an array of N copies, for length limits without N copies in the file.
function expand(value) {
  const m = typeof value === 'string' && value.match(/^@repeat (\d+) (.*)$/s);
  return m ? Array.from({ length: Number(m[1]) }, () => JSON.parse(m[2])) : value;
}
function edit(base, change = {}) {
  const doc = structuredClone(cases.bases[base]);
  for (const [p, value] of Object.entries(change.set || {})) {
    const keys = pointer(p);
    let at = doc;
    for (const k of keys.slice(0, -1)) at = at[k];
    at[keys[keys.length - 1]] = expand(value);
  }
  for (const p of change.delete || []) {
    const keys = pointer(p);
    let at = doc;
    for (const k of keys.slice(0, -1)) at = at[k];
    if (Array.isArray(at)) at.splice(Number(keys[keys.length - 1]), 1);
    else delete at[keys[keys.length - 1]];
  }
  let text = JSON.stringify(doc, null, 2);
  // Texts JSON.parse cannot give back (a key twice, integers past 2^53): a textual edit.
  if (change.raw) {
    check(text.includes(change.raw[0]), `raw edit: ${JSON.stringify(change.raw[0])} not in base ${base}`);
    text = text.replace(change.raw[0], change.raw[1]);
  }
  return text;
}

let sceneNumber = 0;
// The loader's verdict: null when it loads (and builds one frame), else its message.
function load(text) {
  const file = path.join(work, `case-${String(++sceneNumber).padStart(3, '0')}.json`);
  writeFileSync(file, text);
  const r = spawnSync(kodawari, ['run', file, '--frames', '1', '--no-export', '--backend', 'cpu-reference'], { encoding: 'utf8' });
  if (r.status === 0) return null;
  return { status: r.status, message: `${r.stderr}`.trim(), file };
}
function schemaAccepts(text) {
  return validate(JSON.parse(text));
}
// The loader's JSON path ($.a[0]["$schema"]) as the JSON Pointer Ajv reports (/a/0/$schema).
function toPointer(jsonPath) {
  const keys = [];
  for (const m of jsonPath.slice(1).matchAll(/\.([A-Za-z_][A-Za-z0-9_]*)|\[(\d+)\]|\[("(?:[^"\\]|\\.)*")\]/g)) {
    keys.push(m[1] ?? m[2] ?? JSON.parse(m[3]));
  }
  return keys.map((k) => `/${String(k).replace(/~/g, '~0').replace(/\//g, '~1')}`).join('');
}
// Whether one of the schema's errors is about the loader's place: the same value, one
// inside it (an element of a bad array), or its parent (a oneOf, a "not both"). Ajv
// reports unknown and missing keys at the object; they count as the key's own place.
function schemaBlames(jsonPath) {
  const p = toPointer(jsonPath);
  const parent = p.slice(0, p.lastIndexOf('/'));
  return (validate.errors || []).some((e) => {
    const key = e.keyword === 'dependentRequired' ? e.params.property : (e.params.additionalProperty ?? e.params.missingProperty);
    const q = key === undefined ? e.instancePath : `${e.instancePath}/${key}`;
    return q === p || q.startsWith(`${p}/`) || q === parent;
  });
}
function describe(c, base = c.base) {
  const parts = [];
  for (const [p, v] of Object.entries(c.set || {})) parts.push(`${p} = ${JSON.stringify(v).slice(0, 60)}`);
  for (const p of c.delete || []) parts.push(`delete ${p}`);
  if (c.raw) parts.push(`${c.raw[0]} -> ${c.raw[1]}`);
  return `[${base}] ${parts.join(', ')}`;
}

for (const base of Object.keys(cases.bases)) {
  const text = edit(base);
  const loaded = load(text);
  check(loaded === null, `base ${base} should load: ${loaded && loaded.message}`);
  check(schemaAccepts(text), `base ${base} should be valid under the schema: ${schemaErrors()}`);
}

const kinds = new Map();
let goods = 0;
for (const c of cases.cases) {
  const text = edit(c.base, c);
  const loaded = load(text);
  const where = `: ${c.path}: `;
  if (check(loaded !== null, `the loader accepts ${describe(c)} (${c.kind}), expected an error at ${c.path}`)) {
    check(loaded.status === 2 && loaded.message.includes(where),
      `the loader rejects ${describe(c)} (${c.kind}) but not at ${c.path} (status ${loaded.status}): ${loaded.message}`);
  }
  if (check(!schemaAccepts(text), `the schema accepts ${describe(c)} (${c.kind}), which the loader rejects at ${c.path}`)) {
    check(schemaBlames(c.path), `the schema rejects ${describe(c)} (${c.kind}) elsewhere than ${c.path}: ${schemaErrors()}`);
  }
  kinds.set(c.kind, (kinds.get(c.kind) || 0) + 1);
  if (c.good) {
    goods += 1;
    const goodText = edit(c.base, c.good);
    const goodLoaded = load(goodText);
    check(goodLoaded === null, `the loader rejects the good variant ${describe(c.good, c.base)} of ${c.path}: ${goodLoaded && goodLoaded.message}`);
    check(schemaAccepts(goodText), `the schema rejects the good variant ${describe(c.good, c.base)} of ${c.path}: ${schemaErrors()}`);
  }
}
console.log(`bad scenes: ${cases.cases.length} rejected by the loader and the schema (${[...kinds].map(([k, n]) => `${n} ${k}`).join(', ')}); ` +
  `good variants: ${goods} accepted by both`);

console.log('loader rules the schema cannot express (the loader rejects, the schema accepts):');
for (const c of cases.not_expressible) {
  const text = edit(c.base, c);
  const loaded = load(text);
  if (check(loaded !== null, `the loader accepts ${describe(c)}, expected an error at ${c.path} (${c.reason})`)) {
    check(loaded.status === 2 && loaded.message.includes(`: ${c.path}: `),
      `the loader rejects ${describe(c)} but not at ${c.path} (status ${loaded.status}): ${loaded.message}`);
  }
  check(schemaAccepts(text), `the schema now rejects ${describe(c)}: move it from not_expressible to cases (${c.reason})`);
  console.log(`  ${c.path}: ${c.reason}`);
}

// 3. The binary's copy.
const printed = execFileSync(kodawari, ['schema'], { maxBuffer: 64 << 20 });
check(Buffer.compare(printed, schemaBytes) === 0,
  `\`kodawari schema\` (${printed.length} bytes) differs from docs/scene.schema.json (${schemaBytes.length} bytes): rebuild, or the embedding is stale`);
console.log(`kodawari schema: ${printed.length} bytes, the same as docs/scene.schema.json`);
const extra = spawnSync(kodawari, ['schema', 'scenes/flock.json'], { encoding: 'utf8' });
check(extra.status === 2 && extra.stderr.includes('arguments it does not take: scenes/flock.json'),
  `\`kodawari schema SCENE\` should be a usage error (status 2), got status ${extra.status}: ${extra.stderr.split('\n')[0]}`);

if (failures === 0) rmSync(work, { recursive: true, force: true });
else console.log(`(case files kept in ${work})`);
console.log(failures === 0 ? 'schema test: passed' : `schema test: ${failures} check(s) failed`);
process.exit(failures === 0 ? 0 : 1);
