#!/usr/bin/env node
// Checks that our copies of Foxglove's schemas (proto/foxglove/*.proto) are
// Foxglove's: every message against what the npm package @foxglove/schemas
// publishes (docs/foxglove-schemas.md).
//
//   node foxglove_schemas_check.js --modules DIR --proto DIR
//
// --modules: the folder whose node_modules holds protobufjs and
// @foxglove/schemas (the build tree's mcap_reader/, installed by the ctest
// fixture mcap_reader); --proto: the import root of our .proto files (proto/,
// which holds foxglove/). Every proto/foxglove/*.proto is loaded with
// protobufjs, "foxglove/..." imports resolved under --proto (as protoc -I
// does) and google/protobuf/*.proto from protobufjs's bundled well-known
// types. Each file must hold the one message its name says, foxglove.<Name>,
// and for each one:
//   json  against @foxglove/schemas/jsonschema: the same field names; types
//         compatible (double/float <-> number, integers <-> integer, unsigned
//         <-> minimum 0, string, bool <-> boolean, bytes <-> base64 string,
//         google.protobuf.Timestamp/Duration <-> time/duration, messages by
//         title, repeated <-> array, enums by value names and numbers).
//   wire  against the .proto that @foxglove/schemas's own generator
//         (@foxglove/schemas/internal, generateProto: it writes the upstream
//         schemas/proto/foxglove/*.proto) makes for the message, parsed by
//         protobufjs: the same field numbers, proto types, repeated and
//         optional, nested enums' names and values. The JSON Schemas carry no
//         field numbers; this is the check of the wire.
// Prints a table and every difference; exit status 1 on any difference (or a
// message without an upstream schema), 2 on bad arguments or a load failure.
"use strict";

const fs = require("node:fs");
const path = require("node:path");
const { createRequire } = require("node:module");

function usage(msg) {
  if (msg) console.error(`foxglove_schemas_check: ${msg}`);
  console.error("usage: node foxglove_schemas_check.js --modules DIR --proto DIR");
  process.exit(2);
}

const args = { modules: null, proto: null };
for (let i = 2; i < process.argv.length; i++) {
  const a = process.argv[i];
  if (a === "--modules" || a === "--proto") {
    if (i + 1 >= process.argv.length) usage(`${a} needs a folder`);
    args[a.slice(2)] = path.resolve(process.argv[++i]);
  } else if (a === "-h" || a === "--help") {
    usage();
  } else {
    usage(`unknown argument ${a}`);
  }
}
if (!args.modules || !args.proto) usage("--modules and --proto are both needed");

const req = createRequire(path.join(args.modules, "package.json"));
let protobuf, jsonSchemas, internal;
try {
  protobuf = req("protobufjs");
  jsonSchemas = req("@foxglove/schemas/jsonschema");
  internal = req("@foxglove/schemas/internal");
} catch (e) {
  console.error(`foxglove_schemas_check: cannot load protobufjs / @foxglove/schemas from ${args.modules}: ${e.message}`);
  process.exit(2);
}
const schemasVersion = JSON.parse(fs.readFileSync(req.resolve("@foxglove/schemas/package.json"), "utf8")).version;
const protobufVersion = JSON.parse(fs.readFileSync(req.resolve("protobufjs/package.json"), "utf8")).version;

// --- our files --------------------------------------------------------------

const fileDir = path.join(args.proto, "foxglove");
const files = fs.readdirSync(fileDir).filter((f) => f.endsWith(".proto")).sort();
if (files.length === 0) {
  console.error(`foxglove_schemas_check: no .proto files in ${fileDir}`);
  process.exit(2);
}

const ours = new protobuf.Root();
// Like protoc -I <proto>: imports are relative to the import root, not to the
// importing file (google/protobuf/* never reach here: protobufjs bundles them).
ours.resolvePath = (origin, target) => (path.isAbsolute(target) ? target : path.join(args.proto, target));
try {
  ours.loadSync(files.map((f) => path.join(fileDir, f)), { keepCase: true });
  ours.resolveAll();
} catch (e) {
  console.error(`foxglove_schemas_check: protobufjs cannot load ${fileDir}: ${e.message}`);
  process.exit(2);
}
const oursPkg = ours.lookup("foxglove");

// --- upstream's .proto, from their generator ----------------------------------

const theirs = new protobuf.Root();
try {
  theirs.loadSync(["google/protobuf/timestamp.proto", "google/protobuf/duration.proto"]);
  for (const schema of Object.values(internal.foxgloveMessageSchemas)) {
    const enums = Object.values(internal.foxgloveEnumSchemas).filter((e) => e.parentSchemaName === schema.name);
    protobuf.parse(internal.generateProto(schema, enums), theirs, { keepCase: true });
  }
  theirs.resolveAll();
} catch (e) {
  console.error(`foxglove_schemas_check: cannot build @foxglove/schemas's .proto: ${e.message}`);
  process.exit(2);
}

// --- comparisons ------------------------------------------------------------

const INTEGER = new Set(["int32", "sint32", "sfixed32", "int64", "sint64", "sfixed64"]);
const UNSIGNED = new Set(["uint32", "fixed32", "uint64", "fixed64"]);
const FLOATING = new Set(["double", "float"]);

function fieldType(f) {
  return f.resolvedType ? f.resolvedType.fullName.replace(/^\./, "") : f.type;
}
function describe(f) {
  return `${f.repeated ? "repeated " : ""}${fieldType(f)}`;
}
function enumValues(en) {
  return Object.entries(en.values)
    .map(([name, v]) => `${name}=${v}`)
    .sort()
    .join(",");
}

// Why the JSON Schema `p` does not fit one value (not the array) of our field
// `f`, or null when it does.
function jsonValueMismatch(f, p) {
  const t = f.resolvedType;
  if (t instanceof protobuf.Enum) {
    if (!Array.isArray(p.oneOf)) return `enum ${t.name}, theirs ${p.type ?? "no oneOf"}`;
    const theirsValues = p.oneOf
      .map((o) => `${o.title}=${o.const}`)
      .sort()
      .join(",");
    return theirsValues === enumValues(t) ? null : `enum values ${enumValues(t)}, theirs ${theirsValues} (${p.title})`;
  }
  if (t instanceof protobuf.Type) {
    const name = t.fullName.replace(/^\./, "");
    const wanted = { "google.protobuf.Timestamp": "time", "google.protobuf.Duration": "duration" }[name] ?? name;
    if (p.type !== "object") return `${name}, theirs ${p.type}`;
    return p.title === wanted ? null : `${name}, theirs object "${p.title}"`;
  }
  const s = f.type;
  if (FLOATING.has(s)) return p.type === "number" ? null : `${s}, theirs ${p.type}`;
  if (INTEGER.has(s) || UNSIGNED.has(s)) {
    if (p.type !== "integer") return `${s}, theirs ${p.type}`;
    const unsigned = typeof p.minimum === "number" && p.minimum >= 0;
    return unsigned === UNSIGNED.has(s) ? null : `${s}, theirs ${unsigned ? "unsigned" : "signed"} integer`;
  }
  if (s === "bool") return p.type === "boolean" ? null : `bool, theirs ${p.type}`;
  if (s === "string") {
    if (p.type !== "string") return `string, theirs ${p.type}`;
    return p.contentEncoding ? `string, theirs bytes (${p.contentEncoding})` : null;
  }
  if (s === "bytes") {
    if (p.type === "string" && p.contentEncoding === "base64") return null;
    if (p.type === "object" && p.title === "Uint8Array") return null;
    return `bytes, theirs ${p.type}${p.contentEncoding ? ` (${p.contentEncoding})` : ""}`;
  }
  return `${s}: no JSON counterpart known`;
}

function compareJson(msg, schema) {
  const diffs = [];
  const full = `foxglove.${msg.name}`;
  if (schema.title !== full) diffs.push(`title "${schema.title}", ours ${full}`);
  const props = schema.properties ?? {};
  for (const f of msg.fieldsArray) {
    const p = props[f.name];
    if (!p) {
      diffs.push(`${f.name}: ours only`);
      continue;
    }
    let why;
    if (f.repeated) {
      why = p.type !== "array" ? `repeated, theirs ${p.type ?? p.title ?? "?"}` : jsonValueMismatch(f, p.items ?? {});
    } else {
      why = p.type === "array" ? `not repeated, theirs array` : jsonValueMismatch(f, p);
    }
    if (why) diffs.push(`${f.name}: ${why}`);
  }
  for (const name of Object.keys(props)) if (!msg.fields[name]) diffs.push(`${name}: theirs only`);
  return diffs;
}

function compareWire(msg, up) {
  const diffs = [];
  for (const f of msg.fieldsArray) {
    const u = up.fields[f.name];
    if (!u) {
      diffs.push(`${f.name} = ${f.id}: ours only`);
      continue;
    }
    if (u.id !== f.id) diffs.push(`${f.name}: number ${f.id}, theirs ${u.id}`);
    if (describe(u) !== describe(f)) diffs.push(`${f.name}: ${describe(f)}, theirs ${describe(u)}`);
    const opt = (x) => Boolean(x.options && x.options.proto3_optional);
    if (opt(u) !== opt(f)) diffs.push(`${f.name}: ${opt(f) ? "optional" : "not optional"}, theirs the other`);
  }
  for (const u of up.fieldsArray) if (!msg.fields[u.name]) diffs.push(`${u.name} = ${u.id}: theirs only`);
  const nested = (t) => (t.nestedArray ?? []).filter((n) => n instanceof protobuf.Enum);
  const theirEnums = new Map(nested(up).map((e) => [e.name, e]));
  for (const e of nested(msg)) {
    const u = theirEnums.get(e.name);
    if (!u) diffs.push(`enum ${e.name}: ours only`);
    else if (enumValues(u) !== enumValues(e)) diffs.push(`enum ${e.name}: ${enumValues(e)}, theirs ${enumValues(u)}`);
    theirEnums.delete(e.name);
  }
  for (const name of theirEnums.keys()) diffs.push(`enum ${name}: theirs only`);
  return diffs;
}

// --- one row per file -------------------------------------------------------

const rows = [];
for (const file of files) {
  const name = path.basename(file, ".proto");
  const row = { file: `foxglove/${file}`, name, fields: "-", json: [], wire: [], other: [] };
  rows.push(row);
  const msg = oursPkg && oursPkg.nested ? oursPkg.nested[name] : undefined;
  if (!(msg instanceof protobuf.Type)) {
    row.other.push(`no message foxglove.${name} in ${file}`);
    continue;
  }
  if (msg.filename && path.resolve(msg.filename) !== path.join(fileDir, file)) {
    row.other.push(`foxglove.${name} is declared in ${msg.filename}`);
    continue;
  }
  row.fields = String(msg.fieldsArray.length);
  const schema = jsonSchemas[name];
  if (!schema) row.json.push("no JSON schema of that name in @foxglove/schemas");
  else row.json = compareJson(msg, schema);
  const up = theirs.lookup(`foxglove.${name}`);
  if (!(up instanceof protobuf.Type)) row.wire.push("no such message in @foxglove/schemas's generator");
  else row.wire = compareWire(msg, up);
}

// Every message in our package is in a file of its own name (as upstream).
for (const t of Object.values(oursPkg?.nested ?? {})) {
  const own = t.filename ? path.resolve(t.filename) === path.join(fileDir, `${t.name}.proto`) : files.includes(`${t.name}.proto`);
  if (t instanceof protobuf.Type && !own) {
    const where = t.filename ? path.relative(args.proto, t.filename) : "?";
    rows.push({ file: where, name: t.name, fields: String(t.fieldsArray.length), json: [], wire: [],
                other: [`declared in ${where}, not in foxglove/${t.name}.proto`] });
  }
}

const status = (d) => (d.length === 0 ? "match" : `DIFFER (${d.length})`);
const w1 = Math.max(...rows.map((r) => r.name.length), "message".length) + 9;
console.log(`Our proto/foxglove against @foxglove/schemas ${schemasVersion} (protobufjs ${protobufVersion})`);
console.log(`${"message".padEnd(w1)}  ${"fields".padStart(6)}  ${"json schema".padEnd(12)}  wire (numbers, types)`);
for (const r of rows) {
  const json = r.other.length ? "-" : status(r.json);
  const wire = r.other.length ? `DIFFER: ${r.other.join("; ")}` : status(r.wire);
  console.log(`${("foxglove." + r.name).padEnd(w1)}  ${r.fields.padStart(6)}  ${json.padEnd(12)}  ${wire}`);
}
const bad = rows.filter((r) => r.json.length || r.wire.length || r.other.length);
for (const r of bad) {
  console.log(`\nfoxglove.${r.name} (${r.file}):`);
  for (const d of r.other) console.log(`  ${d}`);
  for (const d of r.json) console.log(`  json: ${d}`);
  for (const d of r.wire) console.log(`  wire: ${d}`);
}
console.log(`\nfoxglove_schemas_check: ${rows.length} messages, ${rows.length - bad.length} match, ${bad.length} differ`);
process.exit(bad.length ? 1 : 0);
