#!/usr/bin/env node
// Independent MCAP reader for the tests (@mcap/core from npm, the library
// Foxglove itself uses). Prints {"<topic>": messages, ..., "schemas": n}.
//
//   node read_mcap.js [--stream] [--decode] [--expect expected.json] file.mcap
//
// --decode (indexed files): every message is also decoded with its channel's
// embedded schema (protobuf: protobufjs from the FileDescriptorSet, as
// Foxglove does); any failure is an error, and "decoded" gives the count.
//
// --annotations TOPIC IMAGE_TOPIC (with --decode): the foxglove.ImageAnnotations
// on TOPIC against the pictures on IMAGE_TOPIC, as Foxglove's Image panel pairs
// them (by time): "annotations": {messages, boxes, on_a_picture (messages whose
// time is a picture's publish time), labels (the first few texts)}.
//
// A file that ends with the MCAP magic is opened with McapIndexedReader (footer,
// summary, chunk indexes, every chunk's CRC) and then read again from start to
// end with McapStreamReader, which must agree; the data-section CRC in DataEnd
// and the Statistics record are checked too. A file without the magic at its
// end (a cut-off recording), or any file with --stream, is read with
// McapStreamReader only: every complete record before the cut counts.
// Exit status 1 on any error or disagreement, or when the counts differ from
// --expect.
"use strict";

const fs = require("node:fs");
const zlib = require("node:zlib");
const { McapIndexedReader, McapStreamReader } = require("@mcap/core");
const fzstd = require("fzstd");

const MAGIC = Buffer.from([0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a]);
const decompressHandlers = {
  zstd: (buffer, decompressedSize) => {
    const out = fzstd.decompress(buffer);
    if (BigInt(out.byteLength) !== decompressedSize) {
      throw new Error(`zstd chunk: ${out.byteLength} bytes, expected ${decompressedSize}`);
    }
    return out;
  },
};

function addCount(counts, topic) {
  counts[topic] = (counts[topic] ?? 0) + 1;
}

/// A decoder per schema id (protobuf schemas: protobufjs from the FileDescriptorSet).
function makeDecoder(schema) {
  if (schema.encoding !== "protobuf") throw new Error(`schema ${schema.name}: encoding ${schema.encoding}, not protobuf`);
  const protobuf = require("protobufjs");
  require("protobufjs/ext/descriptor");
  const type = protobuf.Root.fromDescriptor(Buffer.from(schema.data)).lookupType(schema.name);
  return (data) => type.decode(data);
}

async function readIndexed(path, decode, annotations) {
  const handle = await fs.promises.open(path, "r");
  try {
    const readable = {
      size: async () => BigInt((await handle.stat()).size),
      read: async (offset, size) => {
        const buffer = Buffer.alloc(Number(size));
        const { bytesRead } = await handle.read(buffer, 0, buffer.length, Number(offset));
        if (bytesRead !== buffer.length) throw new Error(`short read at ${offset}`);
        return buffer;
      },
    };
    const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
    const counts = {};
    const decoders = new Map();
    let decoded = 0;
    const pictures = new Set();
    const annotated = [];
    for await (const message of reader.readMessages({ validateCrcs: true })) {
      const channel = reader.channelsById.get(message.channelId);
      addCount(counts, channel.topic);
      if (!decode) continue;
      if (!decoders.has(channel.schemaId)) decoders.set(channel.schemaId, makeDecoder(reader.schemasById.get(channel.schemaId)));
      try {
        const m = decoders.get(channel.schemaId)(message.data);
        if (annotations && channel.topic === annotations[1]) pictures.add(message.publishTime);
        if (annotations && channel.topic === annotations[0]) {
          const ts = m.timestamp ? BigInt(m.timestamp.seconds) * 1000000000n + BigInt(m.timestamp.nanos) : 0n;
          if (ts !== message.publishTime) throw new Error(`timestamp ${ts} is not the publish time ${message.publishTime}`);
          annotated.push({ time: message.publishTime, boxes: m.points.length, texts: m.texts.map((t) => t.text) });
        }
      } catch (e) {
        throw new Error(`${channel.topic}: a message at ${message.logTime} does not decode with its schema: ${e.message}`);
      }
      decoded += 1;
    }
    const total = Object.values(counts).reduce((a, b) => a + b, 0);
    const stats = reader.statistics;
    if (!stats) throw new Error("no Statistics record");
    if (stats.messageCount !== BigInt(total)) {
      throw new Error(`Statistics.message_count ${stats.messageCount}, read ${total}`);
    }
    for (const [id, n] of stats.channelMessageCounts) {
      const topic = reader.channelsById.get(id).topic;
      if (n !== BigInt(counts[topic] ?? 0)) throw new Error(`Statistics says ${n} on ${topic}, read ${counts[topic]}`);
    }
    if (reader.dataSectionCrc === undefined) throw new Error("DataEnd has no data section CRC");
    if (typeof zlib.crc32 === "function") {
      const data = fs.readFileSync(path).subarray(0, Number(reader.dataEndOffset));
      const crc = zlib.crc32(data) >>> 0;
      if (crc !== reader.dataSectionCrc) {
        throw new Error(`data section CRC ${crc}, DataEnd says ${reader.dataSectionCrc}`);
      }
    } else {
      process.stderr.write("read_mcap: this node has no zlib.crc32, data section CRC not checked\n");
    }
    const result = { counts, schemas: reader.schemasById.size, chunks: reader.chunkIndexes.length, decoded };
    if (annotations) {
      const labels = annotated.flatMap((a) => a.texts);
      result.annotations = {
        messages: annotated.length,
        boxes: annotated.reduce((n, a) => n + a.boxes, 0),
        on_a_picture: annotated.filter((a) => pictures.has(a.time)).length,
        labels: labels.slice(0, 3),
      };
    }
    return result;
  } finally {
    await handle.close();
  }
}

function readStream(path, requireComplete) {
  const reader = new McapStreamReader({ includeChunks: true, decompressHandlers, validateCrcs: true });
  const topics = new Map();
  const schemas = new Set();
  const counts = {};
  let chunks = 0;
  const fd = fs.openSync(path, "r");
  try {
    const buffer = Buffer.alloc(1 << 20);
    for (;;) {
      const n = fs.readSync(fd, buffer, 0, buffer.length, null);
      if (n === 0) break;
      reader.append(buffer.subarray(0, n));
      for (let record; (record = reader.nextRecord()); ) {
        if (record.type === "Schema") schemas.add(record.id);
        if (record.type === "Channel") topics.set(record.id, record.topic);
        if (record.type === "Chunk") chunks += 1;
        if (record.type === "Message") {
          if (!topics.has(record.channelId)) throw new Error(`message on unknown channel ${record.channelId}`);
          addCount(counts, topics.get(record.channelId));
        }
      }
    }
  } finally {
    fs.closeSync(fd);
  }
  if (requireComplete && !reader.done()) throw new Error("stream reader did not reach the footer");
  return { counts, schemas: schemas.size, chunks, complete: reader.done() };
}

function endsWithMagic(path) {
  const size = fs.statSync(path).size;
  if (size < 2 * MAGIC.length) return false;
  const fd = fs.openSync(path, "r");
  try {
    const tail = Buffer.alloc(MAGIC.length);
    fs.readSync(fd, tail, 0, MAGIC.length, size - MAGIC.length);
    return tail.equals(MAGIC);
  } finally {
    fs.closeSync(fd);
  }
}

function sameJson(a, b) {
  const keys = new Set([...Object.keys(a), ...Object.keys(b)]);
  return [...keys].every((k) => a[k] === b[k]);
}

async function main() {
  const args = process.argv.slice(2);
  let stream = false;
  let decode = false;
  let expectPath;
  let annotations;
  let path;
  for (let i = 0; i < args.length; i++) {
    if (args[i] === "--stream") stream = true;
    else if (args[i] === "--decode") decode = true;
    else if (args[i] === "--expect") expectPath = args[++i];
    else if (args[i] === "--annotations") annotations = [args[++i], args[++i]];
    else if (!path) path = args[i];
    else throw new Error(`unexpected argument ${args[i]}`);
  }
  if (!path) throw new Error("usage: node read_mcap.js [--stream] [--decode] [--expect expected.json] file.mcap");

  let result;
  if (!stream && endsWithMagic(path)) {
    if (annotations && !decode) throw new Error("--annotations needs --decode");
    result = await readIndexed(path, decode, annotations);
    const linear = readStream(path, true);
    if (!sameJson(result.counts, linear.counts) || linear.schemas !== result.schemas || linear.chunks !== result.chunks) {
      throw new Error(`indexed and stream readers disagree: ${JSON.stringify(result)} vs ${JSON.stringify(linear)}`);
    }
  } else {
    result = readStream(path, false);
  }
  const out = { ...result.counts, schemas: result.schemas };
  if (decode) {
    if (result.decoded === undefined) throw new Error("--decode needs a complete (indexed) file");
    out.decoded = result.decoded;
  }
  if (result.annotations) out.annotations = result.annotations;
  process.stdout.write(JSON.stringify(out) + "\n");
  if (expectPath) {
    const expected = JSON.parse(fs.readFileSync(expectPath, "utf8"));
    if (!sameJson(out, expected)) {
      throw new Error(`counts differ from ${expectPath}: expected ${JSON.stringify(expected)}`);
    }
  }
}

main().catch((err) => {
  process.stderr.write(`read_mcap: ${err.message ?? err}\n`);
  process.exit(1);
});
