// A real Foxglove client against `stac view` (tests/web/foxglove_view_test.sh):
//   node foxglove_view.mjs listen URL OUT.json   subscribes to every advertised channel with
//       @foxglove/ws-protocol's FoxgloveClient, decodes each message, checks it against the
//       official JSON schema of its type (@foxglove/schemas), and at SIGTERM writes what arrived
//       (per channel, per scan) to OUT.json, or when the server closes the connection. Prints
//       "subscribed N" once subscribed.
//   node foxglove_view.mjs stall URL          subscribes to every channel, then stops reading its
//       socket: a viewer that hangs. stac view must drop its messages, not the others'.
//   node foxglove_view.mjs misbehave URL      a client without the subprotocol (must be refused),
//       then one that sends garbage, an unknown op and a subscription to no channel (each must
//       be answered with an error status, and the connection kept).
//   node foxglove_view.mjs dump URL           prints the channels and the first message of each
//       (long strings cut), then exits: what docs/view.md shows.
//   node foxglove_view.mjs compare OUT.json DIR  compares OUT.json with what `stac echo` printed
//       for the same scans (DIR/echo_<topic>.txt) and exits 1 on any difference.
import { createRequire } from "node:module";
import fs from "node:fs";

const require = createRequire(import.meta.url);
const { FoxgloveClient } = require("@foxglove/ws-protocol");
const WebSocket = require("ws");
const schemas = require("@foxglove/schemas/jsonschema");

function fail(message) {
  console.error(`foxglove_view: FAIL: ${message}`);
  process.exit(1);
}

// The JSON type of v as JSON schema names it.
function typeOf(v) {
  if (Array.isArray(v)) return "array";
  if (v === null) return "null";
  if (typeof v === "number") return Number.isInteger(v) ? "integer" : "number";
  return typeof v;
}

// Errors of `value` against `schema` (the subset the Foxglove schemas use: type, properties,
// required, items, enum, minimum, maximum).
function validate(schema, value, path, errors) {
  if (schema.type) {
    const t = typeOf(value);
    const ok = schema.type === t || (schema.type === "number" && t === "integer");
    if (!ok) {
      errors.push(`${path}: ${t}, the schema says ${schema.type}`);
      return;
    }
  }
  if (schema.enum && !schema.enum.includes(value)) errors.push(`${path}: ${value} not in enum`);
  if (schema.oneOf && !schema.oneOf.some((s) => s.const === value)) {
    errors.push(`${path}: ${value} is none of the schema's values`);
  }
  if (schema.minimum !== undefined && value < schema.minimum) errors.push(`${path}: below minimum`);
  if (schema.maximum !== undefined && value > schema.maximum) errors.push(`${path}: above maximum`);
  if (schema.type === "object" && schema.properties) {
    for (const key of schema.required ?? []) {
      if (!(key in value)) errors.push(`${path}.${key}: missing (required)`);
    }
    for (const [key, sub] of Object.entries(schema.properties)) {
      if (key in value) validate(sub, value[key], `${path}.${key}`, errors);
    }
  }
  if (schema.type === "array" && schema.items) {
    value.forEach((item, i) => validate(schema.items, item, `${path}[${i}]`, errors));
  }
}

const official = {
  "foxglove.PointCloud": schemas.PointCloud,
  "foxglove.SceneUpdate": schemas.SceneUpdate,
  "foxglove.FrameTransform": schemas.FrameTransform,
};

function listen(url, outFile) {
  const client = new FoxgloveClient({
    ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]),
  });
  const channels = new Map(); // subscription id -> channel
  const out = { serverName: null, channels: [], clouds: [], tracks: [], poses: [], health: [], invalid: [] };
  const decoder = new TextDecoder();
  client.on("serverInfo", (info) => {
    out.serverName = info.name;
  });
  client.on("advertise", (list) => {
    for (const ch of list) {
      out.channels.push({ topic: ch.topic, schemaName: ch.schemaName, encoding: ch.encoding });
      channels.set(client.subscribe(ch.id), ch);
    }
    console.log(`subscribed ${list.length}`);
  });
  client.on("error", (e) => fail(`client error: ${e?.message ?? e}`));
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const ch = channels.get(subscriptionId);
    const msg = JSON.parse(decoder.decode(data));
    const schema = official[ch.schemaName];
    if (schema) {
      const errors = [];
      validate(schema, msg, ch.schemaName, errors);
      if (errors.length > 0) out.invalid.push(...errors.slice(0, 5));
    }
    if (ch.schemaName === "foxglove.PointCloud") {
      const bytes = Buffer.from(msg.data, "base64");
      const byLabel = {};
      const segmentColors = new Map(); // segment id -> its points' colours (one each, expected)
      for (let i = 0; i + msg.point_stride <= bytes.length; i += msg.point_stride) {
        const label = bytes[i + 13];
        byLabel[label] = (byLabel[label] ?? 0) + 1;
        const segment = bytes.readUInt16LE(i + 18);
        const color = `${bytes[i + 14]},${bytes[i + 15]},${bytes[i + 16]},${bytes[i + 17]}`;
        if (!segmentColors.has(segment)) segmentColors.set(segment, new Set());
        segmentColors.get(segment).add(color);
        if ((segment === 65535) !== (label === 0)) {
          out.invalid.push(`scan ${msg.scan_index}: a point with label ${label} in segment ${segment}`);
        }
      }
      const colors = {};
      for (const [segment, set] of segmentColors) colors[segment] = [...set];
      out.clouds.push({
        scan: msg.scan_index,
        points: bytes.length / msg.point_stride,
        byLabel,
        colors,
        fields: msg.fields.map((f) => f.name),
      });
    } else if (ch.schemaName === "foxglove.SceneUpdate") {
      const meta = (e, key) => e.metadata.find((m) => m.key === key)?.value;
      const scan = msg.entities.length > 0 ? Number(meta(msg.entities[0], "scan")) : null;
      out.tracks.push({
        scan,
        timestamp: Number(timestamp),
        deletions: msg.deletions.length,
        objects: msg.entities.map((e) => ({
          id: meta(e, "object_id"),
          cls: meta(e, "class"),
          x: e.cubes[0].pose.position.x,
          y: e.cubes[0].pose.position.y,
          text: e.texts[0].text,
          arrows: e.arrows.length,
          path: e.lines[0].points.length,
        })),
      });
    } else if (ch.schemaName === "foxglove.FrameTransform") {
      out.poses.push({
        t: msg.timestamp.sec + msg.timestamp.nsec * 1e-9,
        parent: msg.parent_frame_id,
        child: msg.child_frame_id,
        x: msg.translation.x,
        y: msg.translation.y,
        z: msg.translation.z,
      });
    } else if (ch.schemaName === "stac.Health") {
      out.health.push({
        scan: msg.scan_index,
        t: msg.timestamp.sec + msg.timestamp.nsec * 1e-9,
        e2e: msg.end_to_end_latency_us,
        misses: msg.deadline_misses,
        model: msg.model_hash,
        sensors: msg.sensors.map((s) => s.name),
      });
    }
  });
  const write = () => {
    fs.writeFileSync(outFile, JSON.stringify(out));
    client.close();
    process.exit(0);
  };
  process.on("SIGTERM", write);
  process.on("SIGINT", write);
  client.on("close", write); // the server stopped (stac demo --view at its end)
}

function stall(url) {
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const client = new FoxgloveClient({ ws });
  client.on("advertise", (list) => {
    for (const ch of list) client.subscribe(ch.id);
    setTimeout(() => {
      ws._socket.pause(); // nothing more is read: the server's data piles up for this client
      setInterval(() => {}, 1000); // a socket that does not read keeps no process alive
      console.log(`subscribed ${list.length} and stalled`);
    }, 100);
  });
  client.on("error", () => {});
  process.on("SIGTERM", () => process.exit(0));
}

async function misbehave(url) {
  const refused = await new Promise((resolve) => {
    const ws = new WebSocket(url); // no subprotocol
    ws.on("open", () => resolve("opened"));
    ws.on("unexpected-response", (_req, res) => resolve(`refused ${res.statusCode}`));
    ws.on("error", (e) => resolve(`error ${e.message}`));
  });
  if (!refused.startsWith("refused 400")) fail(`a client without the subprotocol: ${refused}`);
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const statuses = [];
  await new Promise((resolve) => ws.on("open", resolve));
  ws.on("message", (data, isBinary) => {
    if (isBinary) return;
    const msg = JSON.parse(data.toString());
    if (msg.op === "status") statuses.push(msg);
  });
  ws.send("not json");
  ws.send(JSON.stringify({ op: "publish" }));
  ws.send(JSON.stringify({ op: "subscribe", subscriptions: [{ id: 1, channelId: 99 }] }));
  await new Promise((resolve) => setTimeout(resolve, 500));
  if (statuses.length !== 3 || statuses.some((s) => s.level !== 2)) fail(`statuses: ${JSON.stringify(statuses)}`);
  if (ws.readyState !== WebSocket.OPEN) fail("the connection was closed after bad messages");
  console.log(`misbehave: ${refused}; ${statuses.map((s) => s.message).join(" | ")}`);
  ws.close();
}

function dump(url) {
  const client = new FoxgloveClient({ ws: new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]) });
  const channels = new Map();
  const shown = new Set();
  const cut = (k, v) => (typeof v === "string" && v.length > 60 ? `${v.slice(0, 60)}... (${v.length} chars)` : v);
  client.on("serverInfo", (info) => console.log(`serverInfo: ${info.name}`));
  client.on("advertise", (list) => {
    for (const ch of list) {
      console.log(`channel ${ch.id}: ${ch.topic} ${ch.schemaName} (${ch.encoding})`);
      channels.set(client.subscribe(ch.id), ch);
    }
  });
  client.on("message", ({ subscriptionId, data }) => {
    const ch = channels.get(subscriptionId);
    if (shown.has(ch.topic)) return;
    const msg = JSON.parse(new TextDecoder().decode(data));
    if (ch.schemaName === "foxglove.SceneUpdate") {
      if (msg.entities.length === 0) return;
      msg.entities = [msg.entities[0], `... ${msg.entities.length - 1} more`];
    }
    shown.add(ch.topic);
    console.log(`${ch.topic}: ${JSON.stringify(msg, cut)}`);
    if (shown.size === channels.size) process.exit(0);
  });
}

// Lines of `stac echo` by their scan (or time, for poses).
function echoLines(dir, topic) {
  const file = `${dir}/echo_${topic}.txt`;
  if (!fs.existsSync(file)) fail(`${file} is missing`);
  return fs.readFileSync(file, "utf8").split("\n").filter((l) => l.startsWith(topic));
}

function compare(outFile, dir) {
  const got = JSON.parse(fs.readFileSync(outFile, "utf8"));
  const report = [];
  if (got.invalid.length > 0) fail(`messages that do not fit the official schemas:\n${got.invalid.join("\n")}`);
  const want = ["foxglove.PointCloud", "foxglove.SceneUpdate", "foxglove.FrameTransform", "stac.Health"];
  const advertised = got.channels.map((c) => c.schemaName).sort();
  if (JSON.stringify(advertised) !== JSON.stringify([...want].sort())) fail(`channels: ${advertised}`);
  if (got.channels.some((c) => c.encoding !== "json")) fail("a channel is not JSON");

  // Lines of words equal word by word, numbers within `tol` (one unit of the last digit): a value
  // exactly halfway (55.625 is exact in binary) is rounded to even by echo's printf (55.62) and
  // up by JavaScript's toFixed (55.63).
  const sameWithin = (a, b, tol) =>
    a.length === b.length &&
    a.every((line, i) => {
      const x = line.split(" "), y = b[i].split(" ");
      return x.length === y.length && x.every((w, k) => w === y[k] ||
        (!Number.isNaN(Number(w)) && !Number.isNaN(Number(y[k])) && Math.abs(Number(w) - Number(y[k])) <= tol));
    });

  // Tracks: per scan the count and the first five objects as `stac echo` prints them.
  const tracksEcho = new Map();
  for (const line of echoLines(dir, "tracked_objects")) {
    const scan = Number(/scan (\d+)/.exec(line)[1]);
    const objects = Number(/objects=(\d+)/.exec(line)[1]);
    const firsts = [...line.matchAll(/#(\d+) (\S+) x=(-?[\d.]+) y=(-?[\d.]+)/g)].map((m) => m.slice(1, 5).join(" "));
    tracksEcho.set(scan, { objects, firsts });
  }
  let tracksCompared = 0;
  for (const t of got.tracks) {
    if (t.scan === null || !tracksEcho.has(t.scan)) continue;
    const e = tracksEcho.get(t.scan);
    if (t.objects.length !== e.objects) fail(`scan ${t.scan}: ${t.objects.length} entities, echo ${e.objects}`);
    const firsts = t.objects.slice(0, 5).map((o) => `${o.id} ${o.cls} ${o.x.toFixed(2)} ${o.y.toFixed(2)}`);
    if (!sameWithin(firsts, e.firsts, 0.0101)) {
      fail(`scan ${t.scan}: entities ${JSON.stringify(firsts)}, echo ${JSON.stringify(e.firsts)}`);
    }
    for (const o of t.objects) {
      if (!o.text.startsWith(`#${o.id} ${o.cls} `) || !o.text.endsWith(" m/s")) fail(`text '${o.text}'`);
      if (o.path < 1) fail(`track ${o.id} has no path`);
    }
    if (t.deletions !== 1) fail(`scan ${t.scan}: ${t.deletions} deletions`);
    tracksCompared++;
  }
  const longest = Math.max(0, ...got.tracks.flatMap((t) => t.objects.map((o) => o.path)));
  report.push(`tracked_objects: ${tracksCompared} scans equal (longest path ${longest} points)`);

  // Clouds: per scan the points and the points per label.
  const cloudsEcho = new Map();
  for (const line of echoLines(dir, "point_cloud")) {
    const scan = Number(/scan (\d+)/.exec(line)[1]);
    const points = Number(/points=(\d+)/.exec(line)[1]);
    const none = Number(/none=(\d+)/.exec(line)[1]);
    const labels = /labels=\[([\d,]*)\]/.exec(line)[1].split(",").filter((s) => s !== "").map(Number);
    cloudsEcho.set(scan, { points, byLabel: [none, ...labels] });
  }
  let cloudsCompared = 0;
  for (const c of got.clouds) {
    if (!cloudsEcho.has(c.scan)) continue;
    const e = cloudsEcho.get(c.scan);
    if (c.points !== e.points) fail(`cloud scan ${c.scan}: ${c.points} points, echo ${e.points}`);
    e.byLabel.forEach((n, label) => {
      if ((c.byLabel[label] ?? 0) !== n) fail(`cloud scan ${c.scan}: label ${label}: ${c.byLabel[label]}, echo ${n}`);
    });
    // Coloured by segment: one colour per segment, dark grey outside segments, and segments of
    // consecutive ids told apart.
    for (const [segment, list] of Object.entries(c.colors)) {
      if (list.length !== 1) fail(`cloud scan ${c.scan}: segment ${segment} has colours ${list}`);
    }
    if (c.colors[65535] && c.colors[65535][0] !== "89,89,102,255") fail(`unsegmented points: ${c.colors[65535]}`);
    for (const segment of Object.keys(c.colors).map(Number)) {
      if (segment !== 65535 && c.colors[segment + 1] && c.colors[segment + 1][0] === c.colors[segment][0]) {
        fail(`cloud scan ${c.scan}: segments ${segment} and ${segment + 1} look the same`);
      }
    }
    if (!c.fields.includes("segment")) fail(`cloud fields ${c.fields}`);
    cloudsCompared++;
  }
  report.push(`point_cloud: ${cloudsCompared} scans equal`);

  // Poses: by time (6 decimals), position to 3 decimals.
  const posesEcho = new Map();
  for (const line of echoLines(dir, "ego_pose")) {
    const m = /t=([\d.]+) x=(-?[\d.]+) y=(-?[\d.]+) z=(-?[\d.]+)/.exec(line);
    posesEcho.set(m[1], m.slice(2, 5).join(" "));
  }
  let posesCompared = 0;
  for (const p of got.poses) {
    const key = p.t.toFixed(6);
    if (!posesEcho.has(key)) continue;
    const mine = `${p.x.toFixed(3)} ${p.y.toFixed(3)} ${p.z.toFixed(3)}`;
    if (!sameWithin([mine], [posesEcho.get(key)], 0.00101)) fail(`pose at ${key}: ${mine}, echo ${posesEcho.get(key)}`);
    if (p.child !== "base_link") fail(`pose child frame ${p.child}`);
    posesCompared++;
  }
  report.push(`ego_pose: ${posesCompared} poses equal`);

  // Health: per sample (scan and time: samples between scans repeat the scan) latency, misses
  // and model.
  const healthEcho = new Map();
  for (const line of echoLines(dir, "health")) {
    const m = /scan (\d+) t=([\d.]+) e2e=(\d+)us misses=(\d+) model=([0-9a-f]+)/.exec(line);
    healthEcho.set(`${m[1]} ${m[2]}`, `${m[3]} ${m[4]} ${m[5]}`);
  }
  let healthCompared = 0;
  for (const h of got.health) {
    const key = `${h.scan} ${h.t.toFixed(6)}`;
    if (!healthEcho.has(key)) continue;
    const mine = `${h.e2e} ${h.misses} ${h.model}`;
    if (mine !== healthEcho.get(key)) fail(`health ${key}: ${mine}, echo ${healthEcho.get(key)}`);
    if (!h.sensors.includes("lidar")) fail(`health scan ${h.scan}: sensors ${h.sensors}`);
    healthCompared++;
  }
  report.push(`health: ${healthCompared} samples equal`);

  const minimum = Number(process.env.MIN_MATCHED ?? 10);
  if (Math.min(tracksCompared, cloudsCompared, posesCompared, healthCompared) < minimum) {
    fail(`too few messages matched (at least ${minimum} each): ${report.join("; ")}`);
  }
  console.log(`foxglove_view: ${report.join("; ")}`);
  console.log(`received: ${got.clouds.length} ${got.tracks.length} ${got.poses.length} ${got.health.length}`);
}

const [mode, a, b] = process.argv.slice(2);
if (mode === "listen") listen(a, b);
else if (mode === "stall") stall(a);
else if (mode === "misbehave") misbehave(a);
else if (mode === "dump") dump(a);
else if (mode === "compare") compare(a, b);
else fail("usage: foxglove_view.mjs listen URL OUT.json | compare OUT.json DIR");
