#!/usr/bin/env node
// One camera head as a Foxglove client sees it live (docs/foxglove.md): the
// real client library (@foxglove/ws-protocol over ws) subscribes to a video
// topic and its people annotations, decodes both with the schemas the server
// advertises (protobufjs), decodes the stream from its first keyframe with
// ffmpeg, and pairs each annotation with the picture of the same timestamp,
// as Foxglove's Image panel does.
//
//   node tests/tools/foxglove_camera_check.js --modules DIR --url ws://127.0.0.1:PORT/ --token T
//        --video /robot1/camera_wide --annotations /robot1/camera_wide_people [--seconds 5] [--json FILE]
//
// Prints one JSON line of figures (and writes it to --json): frames,
// keyframes, frames_decoded, frame_id, annotations, boxes, on_a_picture,
// labels; exit status 1 when the topics never appear, 2 on a setup error.
"use strict";

const fs = require("node:fs");
const path = require("node:path");
const os = require("node:os");
const { spawnSync } = require("node:child_process");

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, "")] = process.argv[i + 1];
for (const k of ["modules", "url", "token", "video", "annotations"])
  if (!args[k]) {
    console.error(`foxglove_camera_check: --${k} is required`);
    process.exit(2);
  }
const req = (m) => require(path.join(args.modules, "node_modules", m));
const { FoxgloveClient } = req("@foxglove/ws-protocol");
const { WebSocket } = req("ws");
const protobuf = req("protobufjs");
req("protobufjs/ext/descriptor");

const seconds = Number(args.seconds ?? 5);
const url = `${args.url}${args.url.includes("?") ? "&" : "?"}token=${encodeURIComponent(args.token)}`;
const timeNs = (t) => BigInt(t.seconds ?? 0) * 1000000000n + BigInt(t.nanos ?? 0);

/// NAL unit types of an Annex B buffer.
function nalTypes(buf) {
  const out = [];
  for (let i = 0; i + 3 < buf.length; ++i)
    if (buf[i] === 0 && buf[i + 1] === 0 && (buf[i + 2] === 1 || (buf[i + 2] === 0 && buf[i + 3] === 1))) {
      const h = buf[i + 2] === 1 ? i + 3 : i + 4;
      if (h < buf.length) out.push(buf[h] & 0x1f);
      i = h;
    }
  return out;
}

const fig = { frames: 0, keyframes: 0, frames_decoded: 0, frame_id: "", annotations: 0, boxes: 0, on_a_picture: 0, labels: [] };
const frameTimes = new Set();
const annotationTimes = [];
const stream = []; // Annex B from the first keyframe on
const subs = new Map(); // subscription id -> {topic, type}
const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
const wanted = new Set([args.video, args.annotations]);

client.on("advertise", (channels) => {
  for (const c of channels) {
    if (!wanted.has(c.topic) || [...subs.values()].some((s) => s.topic === c.topic)) continue;
    const type = protobuf.Root.fromDescriptor(Buffer.from(c.schema, "base64")).lookupType(c.schemaName);
    subs.set(client.subscribe(c.id), { topic: c.topic, type });
  }
});
client.on("message", ({ subscriptionId, data }) => {
  const s = subs.get(subscriptionId);
  if (!s) return;
  const msg = s.type.decode(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
  if (s.topic === args.video) {
    ++fig.frames;
    fig.frame_id = msg.frame_id ?? msg.frameId;
    frameTimes.add(timeNs(msg.timestamp));
    const keyframe = nalTypes(msg.data).includes(5);
    if (keyframe) ++fig.keyframes;
    if (keyframe || stream.length) stream.push(Buffer.from(msg.data));
  } else {
    ++fig.annotations;
    fig.boxes += msg.points.length;
    annotationTimes.push(timeNs(msg.timestamp));
    for (const t of msg.texts) if (fig.labels.length < 5) fig.labels.push(t.text);
  }
});
client.on("error", (e) => {
  console.error(`foxglove_camera_check: ${e.message ?? e}`);
  process.exit(2);
});

setTimeout(() => {
  client.close();
  // The pictures an annotation names were received (the last ones may still be on their way).
  fig.on_a_picture = annotationTimes.filter((t) => frameTimes.has(t)).length;
  if (stream.length) {
    const f = path.join(os.tmpdir(), `foxglove-camera-${process.pid}.h264`);
    fs.writeFileSync(f, Buffer.concat(stream));
    const r = spawnSync("ffprobe", ["-v", "error", "-f", "h264", "-count_frames", "-select_streams", "v:0",
      "-show_entries", "stream=nb_read_frames,width,height", "-of", "json", f], { timeout: 20000 });
    fs.rmSync(f, { force: true });
    try {
      const st = JSON.parse(String(r.stdout)).streams[0];
      fig.frames_decoded = Number(st.nb_read_frames);
      fig.width = st.width;
      fig.height = st.height;
    } catch (e) {
      fig.decode_error = String(r.stderr).slice(0, 200);
    }
  }
  const line = JSON.stringify(fig);
  console.log(line);
  if (args.json) fs.writeFileSync(args.json, line + "\n");
  process.exit(fig.frames && subs.size === 2 ? 0 : 1);
}, seconds * 1000);
