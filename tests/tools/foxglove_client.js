#!/usr/bin/env node
// The Foxglove bridge as a Foxglove client sees it (docs/foxglove.md): the
// real client library (@foxglove/ws-protocol over ws), every channel decoded
// with the schema it advertises (protobufjs), rates measured, teleop driven
// and seen in the simulator's ground truth, services called, control refused
// to a second client, an unauthenticated client refused, bad input answered.
//
//   node tests/tools/foxglove_client.js --modules DIR --url ws://127.0.0.1:PORT/ --token T
//        --truth robot1-truth.csv [--robot robot1] [--seconds 6] [--layout LAYOUT.json] [--json FILE]
//
// Prints a table and, with --json, the same figures; exit status 1 when a
// check fails (each failure is printed), 2 on a setup error.
"use strict";

const fs = require("node:fs");
const path = require("node:path");
const os = require("node:os");
const { spawnSync } = require("node:child_process");

const args = {};
for (let i = 2; i < process.argv.length; i += 2) args[process.argv[i].replace(/^--/, "")] = process.argv[i + 1];
const modules = args.modules;
const req = (m) => require(path.join(modules, "node_modules", m));
const { FoxgloveClient } = req("@foxglove/ws-protocol");
const { WebSocket } = req("ws");
const protobuf = req("protobufjs");
req("protobufjs/ext/descriptor");

const robot = args.robot ?? "robot1";
const seconds = Number(args.seconds ?? 6);
const url = args.url;
const token = args.token;
const withToken = (u, t) => `${u}${u.includes("?") ? "&" : "?"}token=${encodeURIComponent(t)}`;

const failures = [];
const figures = {};
function check(ok, what) {
  if (!ok) failures.push(what);
  return ok;
}
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
async function until(pred, ms, step = 20) {
  const end = Date.now() + ms;
  while (Date.now() < end) {
    if (pred()) return true;
    await sleep(step);
  }
  return pred();
}

/// The last truth row: t x y theta wheel_l wheel_r ... (tests/support/stack.hpp's `T` rows).
function truthNow() {
  const text = fs.readFileSync(args.truth, "utf8");
  const lines = text.trimEnd().split("\n");
  for (let i = lines.length - 1; i >= 0; --i) {
    const f = lines[i].split(",");
    if (f[0] === "T" && f.length >= 8) return { t: +f[2], x: +f[3], y: +f[4], wl: +f[6], wr: +f[7] };
  }
  return null;
}

/// Every truth row: CLOCK_MONOTONIC ns (the clock of process.hrtime), the wheels' set-points.
function truthRows() {
  const rows = [];
  for (const line of fs.readFileSync(args.truth, "utf8").split("\n")) {
    const f = line.split(",");
    if (f[0] === "T" && f.length >= 11) rows.push({ mono_ns: Number(f[1]), setL: +f[8], setR: +f[9] });
  }
  return rows;
}

/// A connection that refuses: resolves with the error text (or "" when it opened).
function tryConnect(u, protocols) {
  return new Promise((resolve) => {
    const ws = new WebSocket(u, protocols);
    ws.on("open", () => {
      ws.close();
      resolve("");
    });
    ws.on("error", (e) => resolve(String(e.message)));
  });
}

class Session {
  constructor(name, protocols = [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) {
    this.name = name;
    this.channels = new Map(); // id -> channel
    this.types = new Map(); // subscription id -> {topic, type}
    this.counts = {};
    this.times = {};
    this.decodeErrors = 0;
    this.statuses = [];
    this.services = new Map(); // name -> service
    this.pending = new Map(); // callId -> resolve
    this.nextCall = 1;
    this.latest = {};
    this.keyframes = [];
    this.cameraFrames = 0;
    this.client = new FoxgloveClient({ ws: new WebSocket(withToken(url, token), protocols) });
    this.opened = new Promise((resolve, reject) => {
      this.client.on("open", resolve);
      this.client.on("error", (e) => reject(e));
    });
    this.client.on("serverInfo", (i) => (this.serverInfo = i));
    this.client.on("status", (s) => this.statuses.push(s));
    this.client.on("advertise", (chs) => {
      for (const c of chs) this.channels.set(c.id, c);
    });
    this.client.on("unadvertise", (ids) => {
      for (const id of ids) this.channels.delete(id);
    });
    this.client.on("advertiseServices", (ss) => {
      for (const s of ss) this.services.set(s.name, s);
    });
    this.client.on("message", ({ subscriptionId, data }) => this.onMessage(subscriptionId, data));
    this.client.on("serviceCallResponse", (r) => {
      const done = this.pending.get(r.callId);
      if (!done) return;
      this.pending.delete(r.callId);
      done(JSON.parse(Buffer.from(r.data.buffer, r.data.byteOffset, r.data.byteLength).toString("utf8")));
    });
    this.client.on("serviceCallFailure", (f) => {
      const done = this.pending.get(f.callId);
      if (!done) return;
      this.pending.delete(f.callId);
      done({ ok: false, message: f.message, failure: true });
    });
  }
  subscribeAll() {
    for (const [id, c] of this.channels) {
      if ([...this.types.values()].some((t) => t.channel === id)) continue;
      if (c.encoding !== "protobuf") {
        failures.push(`${c.topic}: encoding ${c.encoding}, expected protobuf`);
        continue;
      }
      let type;
      try {
        type = protobuf.Root.fromDescriptor(Buffer.from(c.schema, "base64")).lookupType(c.schemaName);
      } catch (e) {
        failures.push(`${c.topic}: schema ${c.schemaName} does not load: ${e.message}`);
        continue;
      }
      this.types.set(this.client.subscribe(id), { channel: id, topic: c.topic, type });
    }
  }
  onMessage(sub, data) {
    const t = this.types.get(sub);
    if (!t) return;
    const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
    let msg;
    try {
      msg = t.type.decode(bytes);
    } catch (e) {
      ++this.decodeErrors;
      return;
    }
    this.counts[t.topic] = (this.counts[t.topic] ?? 0) + 1;
    (this.times[t.topic] ??= []).push(Date.now());
    this.latest[t.topic] = msg;
    if (t.topic.endsWith("/camera")) {
      ++this.cameraFrames;
      const nals = nalTypes(msg.data);
      if (nals.includes(5)) this.keyframes.push({ data: Buffer.from(msg.data), sps: nals.includes(7), pps: nals.includes(8) });
    }
  }
  call(name, request, timeoutMs = 3000) {
    const s = this.services.get(name);
    if (!s) return Promise.resolve({ ok: false, message: `no service ${name}` });
    const callId = this.nextCall++;
    return new Promise((resolve) => {
      this.pending.set(callId, resolve);
      this.client.sendServiceCallRequest({
        serviceId: s.id,
        callId,
        encoding: "json",
        data: new Uint8Array(Buffer.from(JSON.stringify(request))),
      });
      setTimeout(() => {
        if (this.pending.delete(callId)) resolve({ ok: false, message: `${name}: no response within ${timeoutMs} ms` });
      }, timeoutMs);
    });
  }
  rate(topic, fromMs, toMs) {
    const ts = (this.times[topic] ?? []).filter((t) => t >= fromMs && t <= toMs);
    return ts.length / ((toMs - fromMs) / 1000);
  }
  mode() {
    const t = this.latest[`/${robot}/telemetry`];
    return t ? t.mode : -1;
  }
  close() {
    this.client.close();
  }
}

function nalTypes(buf) {
  const out = [];
  for (let i = 0; i + 3 < buf.length; ++i) {
    if (buf[i] === 0 && buf[i + 1] === 0 && (buf[i + 2] === 1 || (buf[i + 2] === 0 && buf[i + 3] === 1))) {
      const h = buf[i + 2] === 1 ? i + 3 : i + 4;
      if (h < buf.length) out.push(buf[h] & 0x1f);
      i = h;
    }
  }
  return out;
}

/// Decodes one keyframe alone with FFmpeg (the real decoder): true when it gives a picture.
function keyframeDecodes(data) {
  const f = path.join(os.tmpdir(), `fox-kf-${process.pid}-${Math.random().toString(36).slice(2)}.h264`);
  fs.writeFileSync(f, data);
  const r = spawnSync("ffmpeg", ["-v", "error", "-f", "h264", "-i", f, "-frames:v", "1", "-f", "null", "-"], {
    timeout: 10000,
  });
  fs.rmSync(f, { force: true });
  return r.status === 0 && String(r.stderr).trim() === "";
}

const MODE = { IDLE: 1, TELEOP: 2, ESTOP: 3 };

async function main() {
  // 1. Without the token, with a wrong one, with no known subprotocol: refused before the upgrade.
  const noToken = await tryConnect(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  check(/401/.test(noToken), `no token: expected HTTP 401, got '${noToken}'`);
  const wrong = await tryConnect(withToken(url, "x".repeat(32)), [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  check(/401/.test(wrong), `wrong token: expected HTTP 401, got '${wrong}'`);
  const noProto = await tryConnect(withToken(url, token), ["some.other.protocol"]);
  check(/400/.test(noProto), `unknown subprotocol: expected HTTP 400, got '${noProto}'`);
  const sdk = await tryConnect(withToken(url, token), ["foxglove.sdk.v1"]);
  check(sdk === "", `subprotocol foxglove.sdk.v1: expected to connect, got '${sdk}'`);

  // 2. A client that subscribes to every channel and decodes everything.
  const a = new Session("A");
  await a.opened;
  await until(() => a.serverInfo && a.channels.size >= 10 && a.services.size > 0, 5000);
  check(a.serverInfo && a.serverInfo.capabilities.includes("clientPublish") && a.serverInfo.capabilities.includes("services"),
        `serverInfo capabilities: ${JSON.stringify(a.serverInfo && a.serverInfo.capabilities)}`);
  check(a.serverInfo && a.serverInfo.sessionId, "serverInfo has no sessionId");
  for (const t of ["telemetry", "events", "acks", "alarms", "camera", "camera_people", "tf", "scene", "log", "video_stats"])
    check([...a.channels.values()].some((c) => c.topic === `/${robot}/${t}`), `no channel /${robot}/${t}`);
  for (const s of ["/stop", "/estop", "/resume", "/goto", "/route", "/inspect", "/record_start", "/record_stop", "/alarm_ack",
                   "/control_take", "/control_release"])
    check(a.services.has(s), `no service ${s}`);
  a.subscribeAll();
  // The shipped layout (config/foxglove/inspect_live.json) names only topics and services the bridge serves.
  if (args.layout) {
    const names = new Set();
    const walk = (v) => {
      if (typeof v === "string" && v.startsWith(`/${robot}/`)) names.add(v.split(".")[0]);
      else if (v && typeof v === "object") for (const [k, x] of Object.entries(v)) (walk(k), walk(x));
    };
    walk(JSON.parse(fs.readFileSync(args.layout, "utf8")));
    const topics = new Set([...a.channels.values()].map((c) => c.topic));
    for (const n of names)
      check(topics.has(n) || n === `/${robot}/cmd_vel` || n.startsWith(`/${robot}/gas/`), `layout names ${n}, which the bridge does not advertise`);
    const layout = JSON.parse(fs.readFileSync(args.layout, "utf8"));
    for (const [id, cfg] of Object.entries(layout.configById ?? {}))
      if (id.startsWith("CallService") && cfg.serviceName) check(a.services.has(cfg.serviceName), `layout calls ${cfg.serviceName}, no such service`);
    figures.layout_topics = names.size;
  }
  const t0 = Date.now();
  await sleep(seconds * 1000);
  const t1 = Date.now();
  a.subscribeAll(); // channels that appeared meanwhile (gas grids)
  await sleep(1500);
  const tel = a.rate(`/${robot}/telemetry`, t0 + 500, t1);
  const cam = a.rate(`/${robot}/camera`, t0 + 1500, t1);
  const scn = a.rate(`/${robot}/scene`, t0 + 500, t1);
  const tf = a.rate(`/${robot}/tf`, t0 + 500, t1);
  figures.telemetry_hz = +tel.toFixed(1);
  figures.camera_fps = +cam.toFixed(1);
  figures.scene_hz = +scn.toFixed(1);
  figures.tf_hz = +tf.toFixed(1);
  figures.decode_errors = a.decodeErrors;
  figures.messages = a.counts;
  check(tel >= 45, `telemetry ${tel.toFixed(1)} Hz < 45`);
  check(cam >= 25, `video ${cam.toFixed(1)} fps < 25`);
  check(scn >= 5, `scene ${scn.toFixed(1)} Hz < 5`);
  check(a.decodeErrors === 0, `${a.decodeErrors} messages did not decode with their schema`);
  check(Object.keys(a.counts).some((t) => t.includes("/gas/")), "no gas grid received");
  // The video path as a whole once a second: the robot's rate in force and the server's receive figures.
  const vs = a.latest[`/${robot}/video_stats`];
  figures.video_stats = vs ? { rate_kbps: vs.sender?.rate_kbps, rate_reason: vs.sender?.rate_reason,
                               fps_decoded: vs.receiver?.fps_decoded, latency_p50_ms: vs.receiver?.latency_p50_ms } : null;
  check(vs && vs.sender && vs.sender.rate_kbps > 0 && vs.sender.rate_reason, `video_stats: no sender rate (${JSON.stringify(vs)})`);
  check(vs && vs.receiver && vs.receiver.fps_decoded > 0, `video_stats: no receiver figures (${JSON.stringify(vs)})`);
  const scene = a.latest[`/${robot}/scene`];
  const ids = scene ? scene.entities.map((e) => e.id) : [];
  figures.scene_entities = ids;
  for (const id of ["robot/body", "robot/sonar_fl", "robot/sonar_fr", "robot/sonar_l", "robot/sonar_r", "route", "people"])
    check(ids.includes(id), `scene has no entity ${id}`);
  const tfs = a.latest[`/${robot}/tf`];
  const frames = tfs ? tfs.transforms.map((x) => x.childFrameId ?? x.child_frame_id) : [];
  for (const f of ["odom", "base_link", "sonar_fl", "camera_mount", "camera"])
    check(frames.includes(`${robot}/${f}`), `transforms have no ${robot}/${f}`);
  // Every keyframe carries SPS and PPS and decodes on its own.
  figures.keyframes = a.keyframes.length;
  check(a.keyframes.length >= 1, "no keyframe received");
  let decodable = 0;
  for (const k of a.keyframes) {
    check(k.sps && k.pps, "a keyframe without SPS/PPS");
    if (keyframeDecodes(k.data)) ++decodable;
  }
  figures.keyframes_decodable = decodable;
  check(decodable === a.keyframes.length, `${a.keyframes.length - decodable} of ${a.keyframes.length} keyframes do not decode`);

  // 3. Teleop from the client (the Teleop panel's Twist JSON at 10 Hz): the robot moves in the ground truth.
  const before = truthNow();
  const cmd = a.client.advertise({ topic: `/${robot}/cmd_vel`, encoding: "json", schemaName: "geometry_msgs/Twist" });
  const twist = (v, w) => new Uint8Array(Buffer.from(JSON.stringify({ linear: { x: v, y: 0, z: 0 }, angular: { x: 0, y: 0, z: w } })));
  let sawTeleop = false;
  let lastSendNs = 0;
  for (let i = 0; i < 20; ++i) {
    a.client.sendMessage(cmd, twist(0.3, 0.0));
    lastSendNs = Number(process.hrtime.bigint());
    await sleep(100);
    sawTeleop ||= a.mode() === MODE.TELEOP;
  }
  const moved = truthNow();
  const dist = Math.hypot(moved.x - before.x, moved.y - before.y);
  figures.teleop_distance_m = +dist.toFixed(3);
  check(sawTeleop, "telemetry never showed TELEOP while the client drove");
  check(dist > 0.2, `teleop moved the robot ${dist.toFixed(3)} m in 2 s at 0.3 m/s (truth)`);
  // The client stops sending: the set-point lapses (deadman) and the robot stops.
  const lapseStart = Date.now();
  const stopped = await until(() => {
    const r = truthNow();
    return r && Math.abs(r.wl) < 0.05 && Math.abs(r.wr) < 0.05;
  }, 3000, 50);
  figures.deadman_stop_ms = Date.now() - lapseStart;
  check(stopped, "the robot did not stop within 3 s after the client stopped sending teleop");
  // From the last message, in the ground truth (same monotonic clock): the
  // set-points start down when the 0.3 s lease lapses and reach zero after
  // the ramp (0.3 m/s = 1.5 rad/s at 10 rad/s^2: 0.15 s).
  await sleep(200);  // the truth log is written every few tens of ms
  const after = truthRows().filter((r) => r.mono_ns > lastSendNs);
  const driving = after.length ? Math.max(Math.abs(after[0].setL), Math.abs(after[0].setR)) : 0;
  const down = after.find((r) => Math.max(Math.abs(r.setL), Math.abs(r.setR)) < driving - 1e-6);
  const zero = after.find((r) => r.setL === 0 && r.setR === 0);
  figures.deadman_ramp_start_ms = down ? +((down.mono_ns - lastSendNs) / 1e6).toFixed(1) : -1;
  figures.deadman_setpoints_zero_ms = zero ? +((zero.mono_ns - lastSendNs) / 1e6).toFixed(1) : -1;
  check(driving > 1.0, `the set-points were not driving after the last message (${driving} rad/s)`);
  check(down && figures.deadman_ramp_start_ms <= 380,
        `the stop started ${figures.deadman_ramp_start_ms} ms after the last teleop message (lease 300 ms)`);
  check(zero && figures.deadman_setpoints_zero_ms <= 560,
        `the set-points reached zero ${figures.deadman_setpoints_zero_ms} ms after the last teleop message (lease 300 + ramp 150 ms)`);
  check(a.statuses.some((s) => /teleop: no set-point/.test(s.message)), "no status saying the teleop set-point lapsed");

  // 4. A second client: observes; its motion is refused with the holder's name; stop always works.
  const b = new Session("B");
  await b.opened;
  await until(() => b.channels.size >= 8 && b.services.size > 0, 5000);
  const bcmd = b.client.advertise({ topic: `/${robot}/cmd_vel`, encoding: "json", schemaName: "geometry_msgs/Twist" });
  b.client.sendMessage(bcmd, twist(0.3, 0));
  await until(() => b.statuses.some((s) => /teleop refused/.test(s.message)), 2000);
  const refusal = b.statuses.find((s) => /teleop refused/.test(s.message));
  figures.refusal = refusal ? refusal.message : "";
  check(refusal && /foxglove 127\.0\.0\.1/.test(refusal.message), `B's teleop refusal does not name the holder: '${figures.refusal}'`);
  const bgoto = await b.call("/goto", { x: 1, y: 0 });
  check(!bgoto.ok && /control/.test(bgoto.message), `B's /goto without control: ${JSON.stringify(bgoto)}`);
  const bstop = await b.call("/stop", {});
  // The operator service answers once the robot's Ack is in.
  check(bstop.ok && /stop accepted/.test(bstop.message), `B's /stop: ${JSON.stringify(bstop)}`);

  // 5. E-stop and resume from the controlling client; then release.
  const estop = await a.call("/estop", {});
  check(estop.ok && /estop accepted/.test(estop.message), `/estop: ${JSON.stringify(estop)}`);
  check(await until(() => a.mode() === MODE.ESTOP, 2000), "telemetry did not show ESTOP after /estop");
  const resume = await a.call("/resume", {});
  check(resume.ok, `/resume: ${JSON.stringify(resume)}`);
  check(await until(() => a.mode() === MODE.IDLE, 2000), "telemetry did not show IDLE after /resume");
  // Recording and routes are typed calls of the operator service as well.
  const rec = await a.call("/record_start", { name: "foxglove check" });
  check(rec.ok && new RegExp(`^${robot}: recording run \\S+$`).test(rec.message), `/record_start: ${JSON.stringify(rec)}`);
  const recStop = await a.call("/record_stop", {});
  check(recStop.ok && /^\S+: run \S+ stopped$/.test(recStop.message), `/record_stop: ${JSON.stringify(recStop)}`);
  const recAgain = await a.call("/record_stop", {});
  check(!recAgain.ok && /is not recording/.test(recAgain.message), `a second /record_stop: ${JSON.stringify(recAgain)}`);
  const noRoute = await a.call("/route", { route: "no_such_route" });
  check(!noRoute.ok && /^route: no route 'no_such_route'/.test(noRoute.message), `/route to no route: ${JSON.stringify(noRoute)}`);
  const labRound = path.resolve(__dirname, "../../config/routes/gas_lab_inspection.yaml");
  const fast = await a.call("/inspect", { route: labRound, speed: 3 });
  check(!fast.ok && /speed_m_s '3' must be a number in \(0, 1\]/.test(fast.message), `/inspect too fast: ${JSON.stringify(fast)}`);
  const noAlarm = await a.call("/alarm_ack", {});
  check(!noAlarm.ok && noAlarm.message === "ack: nothing to acknowledge", `/alarm_ack without alarms: ${JSON.stringify(noAlarm)}`);
  const bad = await a.call("/goto", { x: "one" });
  check(!bad.ok && /number/.test(bad.message), `/goto with a bad request: ${JSON.stringify(bad)}`);
  const rel = await a.call("/control_release", {});
  check(rel.ok, `/control_release: ${JSON.stringify(rel)}`);

  // 6. Bad input: each answered with a status naming it; the connection and the others go on.
  const raw = new WebSocket(withToken(url, token), [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const rawStatus = [];
  let rawClose = null;
  raw.on("message", (d, isBinary) => {
    if (!isBinary) {
      const m = JSON.parse(String(d));
      if (m.op === "status") rawStatus.push(m.message);
    }
  });
  raw.on("close", (code) => (rawClose = code));
  await new Promise((r) => raw.on("open", r));
  const probes = [
    ["{not json", /malformed JSON/],
    [JSON.stringify({ op: "dance" }), /unknown op/],
    [JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: 99999 }] }), /not advertised/],
    [JSON.stringify({ op: "subscribe", subscriptions: "all" }), /must be an array/],
    [JSON.stringify({ op: "getParameters", parameterNames: [] }), /capability 'parameters'/],
    [Buffer.from([0x01, 0x07, 0, 0, 0, 1, 2]), /did not advertise/],
    [Buffer.from([0x02, 1, 0, 0, 0, 1, 0, 0, 0, 0xff, 0, 0, 0]), /runs past/],
    [Buffer.from([0x02, 1, 0]), /needs at least 13/],
    [Buffer.from([0x09]), /unknown binary opcode/],
  ];
  for (const [p, re] of probes) {
    const n = rawStatus.length;
    raw.send(p);
    await until(() => rawStatus.length > n, 1000);
    check(rawStatus.slice(n).some((m) => re.test(m)), `bad input ${String(p).slice(0, 40)}: status ${JSON.stringify(rawStatus.slice(n))}`);
  }
  // A flood: refused past the rate with one status naming it.
  for (let i = 0; i < 1500; ++i) raw.send(JSON.stringify({ op: "unsubscribe", subscriptionIds: [] }));
  await until(() => rawStatus.some((m) => /too many requests/.test(m)), 2000);
  check(rawStatus.some((m) => /too many requests/.test(m)), "a flood of requests got no 'too many requests' status");
  // An oversized message closes the connection (1009, message too big), as the WebSocket spec says.
  raw.send("x".repeat(200 * 1024));
  await until(() => rawClose !== null, 2000);
  figures.oversized_close_code = rawClose;
  check(rawClose === 1009, `oversized message: close code ${rawClose}, expected 1009`);
  // Client A still receives telemetry.
  const na = a.counts[`/${robot}/telemetry`];
  await sleep(500);
  check(a.counts[`/${robot}/telemetry`] > na, "client A stopped receiving telemetry after another client's bad input");

  a.close();
  b.close();
  return figures;
}

const timer = setTimeout(() => {
  console.error("foxglove_client: timed out after 90 s");
  process.exit(2);
}, 90000);
main()
  .then((f) => {
    clearTimeout(timer);
    const rows = [
      ["telemetry", `${f.telemetry_hz} Hz`, ">= 45"],
      ["camera", `${f.camera_fps} fps`, ">= 25"],
      ["scene", `${f.scene_hz} Hz`, ">= 5"],
      ["transforms", `${f.tf_hz} Hz`, ""],
      ["keyframes decodable", `${f.keyframes_decodable} / ${f.keyframes}`, "all"],
      ["decode errors", `${f.decode_errors}`, "0"],
      ["teleop distance (truth)", `${f.teleop_distance_m} m`, "> 0.2"],
      ["deadman stop", `${f.deadman_stop_ms} ms`, "< 3000"],
      ["oversized close code", `${f.oversized_close_code}`, "1009"],
    ];
    console.log("foxglove_client: figure                    value         target");
    for (const [a, b, c] of rows) console.log(`  ${a.padEnd(26)} ${b.padEnd(13)} ${c}`);
    console.log(`  messages per topic: ${JSON.stringify(f.messages)}`);
    if (args.json) fs.writeFileSync(args.json, JSON.stringify({ figures: f, failures }, null, 2));
    for (const x of failures) console.log(`FAIL: ${x}`);
    console.log(failures.length ? `foxglove_client: ${failures.length} checks failed` : "foxglove_client: all checks passed");
    process.exit(failures.length ? 1 : 0);
  })
  .catch((e) => {
    console.error(`foxglove_client: ${e.stack ?? e}`);
    process.exit(2);
  });
