#!/usr/bin/env node
// Independent checker for flowsteer's simulation MCAP recordings (see README.md).
// usage: node check_mcap.mjs RUN.mcap TRAJECTORIES.csv
// Prints a JSON object of message counts per topic and "ok"; exits 1 with the reasons on failure.
import { readFileSync } from "node:fs";
import { McapIndexedReader, McapStreamReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse as parseMsgDef } from "@foxglove/rosmsg";
import { MessageReader } from "@foxglove/rosmsg2-serialization";
import { crc32 } from "@foxglove/crc";
import foxgloveJsonSchemas from "@foxglove/schemas/jsonschema.js";
import AjvModule from "ajv";
import Ajv2019Module from "ajv/dist/2019.js";
import Ajv2020Module from "ajv/dist/2020.js";

const Ajv = AjvModule.default ?? AjvModule;
const Ajv2019 = Ajv2019Module.default ?? Ajv2019Module;
const Ajv2020 = Ajv2020Module.default ?? Ajv2020Module;

const TOL = 1e-9;
const PNG_MAGIC = [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];
const MAX_REPORTED = 40;
const errors = [];
let dataCrcError; // reported with the chunk/stream errors so that both show up


function fail(msg) {
  errors.push(msg);
}
function die(msg) {
  if (msg) errors.push(msg);
  if (dataCrcError) errors.push(dataCrcError);
  dataCrcError = undefined;
  const shown = errors.slice(0, MAX_REPORTED);
  for (const e of shown) console.error(`check_mcap: FAIL: ${e}`);
  if (errors.length > shown.length) console.error(`check_mcap: ... and ${errors.length - shown.length} more failures`);
  process.exit(1);
}
function bail() {
  if (errors.length > 0) die();
}

const [, , mcapPath, csvPath] = process.argv;
if (!mcapPath || !csvPath) {
  console.error("usage: node check_mcap.mjs RUN.mcap TRAJECTORIES.csv");
  process.exit(2);
}

// ---------------------------------------------------------------------------- trajectories.csv
function readCsv(path) {
  const lines = readFileSync(path, "utf8").split(/\r?\n/).filter((l) => l.trim() !== "");
  if (lines.length === 0) die(`${path}: empty`);
  const header = lines[0].split(",").map((s) => s.trim());
  const need = ["t", "agent", "x", "y", "heading", "v", "a_c", "omega"];
  const col = {};
  for (const name of need) {
    col[name] = header.indexOf(name);
    if (col[name] < 0) die(`${path}: header lacks column "${name}" (header: ${lines[0]})`);
  }
  const rows = [];
  for (let i = 1; i < lines.length; i++) {
    const f = lines[i].split(",");
    const num = (name) => {
      const v = Number(f[col[name]]);
      if (f[col[name]] === undefined || f[col[name]].trim() === "" || Number.isNaN(v)) {
        die(`${path}:${i + 1}: bad value for ${name}: ${JSON.stringify(f[col[name]])}`);
      }
      return v;
    };
    const agent = num("agent");
    if (!Number.isInteger(agent) || agent < 0) die(`${path}:${i + 1}: bad agent index ${f[col.agent]}`);
    rows.push({ line: i + 1, t: num("t"), agent, x: num("x"), y: num("y"), heading: num("heading"), v: num("v") });
  }
  return rows;
}

// ---------------------------------------------------------------------------- helpers
const tNs = (t) => BigInt(Math.round(t * 1e9));
const stampNs = (s) => BigInt(s.sec) * 1000000000n + BigInt(s.nanosec);
const angleDiff = (a, b) => Math.abs(Math.atan2(Math.sin(a - b), Math.cos(a - b)));
const yawOf = (q) => Math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z));
const near = (a, b) => Math.abs(a - b) <= TOL;

function makeReadable(buf) {
  return {
    size: async () => BigInt(buf.length),
    read: async (offset, size) => {
      const start = Number(offset);
      const end = start + Number(size);
      if (start < 0 || end > buf.length) throw new Error(`read [${start}, ${end}) outside the file (${buf.length} bytes)`);
      return buf.subarray(start, end);
    },
  };
}

function ajvFor(schema) {
  const draft = typeof schema.$schema === "string" ? schema.$schema : "";
  const opts = { strict: false, allErrors: true };
  if (draft.includes("2020-12")) return new Ajv2020(opts);
  if (draft.includes("2019-09")) return new Ajv2019(opts);
  if (draft === "" || draft.includes("draft-07") || draft.includes("draft-06")) return new Ajv(opts);
  throw new Error(`unsupported JSON Schema dialect ${draft}`);
}
const ajvErrors = (validate) =>
  (validate.errors ?? []).slice(0, 5).map((e) => `${e.instancePath || "/"} ${e.message}`).join("; ");

// ---------------------------------------------------------------------------- main
const buf = readFileSync(mcapPath);
const rows = readCsv(csvPath);
const decompressHandlers = await loadDecompressHandlers();

// 1. Indexed reader: summary, summary CRC (checked by Initialize), chunk CRCs (validateCrcs).
let reader;
try {
  reader = await McapIndexedReader.Initialize({ readable: makeReadable(buf), decompressHandlers });
} catch (e) {
  die(`McapIndexedReader: ${e.message}`);
}
if (reader.header.profile !== "ros2") fail(`header profile is "${reader.header.profile}", expected "ros2"`);
if (!reader.header.library.startsWith("flowsteer")) fail(`header library is "${reader.header.library}", expected "flowsteer <version>"`);
if (reader.footer.summaryStart === 0n) fail("no summary section");
if (reader.footer.summaryCrc === 0) fail("footer summary_crc is 0 (CRCs are required)");
if (reader.footer.summaryOffsetStart === 0n) fail("no summary offsets");
if (!reader.statistics) fail("no statistics record in the summary");
if (reader.chunkIndexes.length === 0) fail("no chunk indexes (the file must be chunked)");
for (const ci of reader.chunkIndexes) {
  if (ci.compression !== "zstd" && ci.compression !== "") {
    fail(`chunk at ${ci.chunkStartOffset} uses compression "${ci.compression}", expected "zstd" or ""`);
  }
}
if (!reader.metadataIndexes.some((m) => m.name === "flowsteer")) fail('no metadata index entry "flowsteer"');
// Data section CRC (DataEnd): neither @mcap/core reader checks it, so compute it here.
if (reader.dataSectionCrc === undefined) {
  fail("DataEnd data_section_crc is 0 (CRCs are required)");
} else {
  const actual = crc32(buf.subarray(0, Number(reader.dataEndOffset)));
  if (actual !== reader.dataSectionCrc) dataCrcError = `data section CRC ${actual} != DataEnd's ${reader.dataSectionCrc}`;
}
if (errors.length > 0) die();

// Metadata.
const meta = [];
for await (const m of reader.readMetadata({ name: "flowsteer" })) meta.push(m);
if (meta.length !== 1) die(`expected one "flowsteer" metadata record, found ${meta.length}`);
const md = meta[0].metadata;
for (const key of ["version", "clock", "agents"]) if (!md.has(key)) fail(`metadata "flowsteer" lacks key "${key}"`);
bail();
if (!["simulation", "monotonic"].includes(md.get("clock"))) fail(`metadata clock "${md.get("clock")}" is not simulation|monotonic`);
let agents;
try {
  agents = JSON.parse(md.get("agents"));
} catch (e) {
  die(`metadata agents is not JSON: ${e.message}`);
}
if (!Array.isArray(agents) || !agents.every((a) => typeof a === "string" && /^[A-Za-z_][A-Za-z0-9_]*$/.test(a))) {
  die(`metadata agents must be a JSON array of namespaces [A-Za-z_][A-Za-z0-9_]*, got ${md.get("agents")}`);
}
if (new Set(agents).size !== agents.length) die(`metadata agents has duplicates: ${md.get("agents")}`);

// Channel decoders.
const decoders = new Map(); // channel id -> (data: Uint8Array) => decoded
for (const [id, ch] of reader.channelsById) {
  const schema = reader.schemasById.get(ch.schemaId);
  const where = `channel ${id} "${ch.topic}"`;
  if (!schema) {
    fail(`${where}: schema ${ch.schemaId} not found`);
    continue;
  }
  const schemaText = new TextDecoder().decode(schema.data);
  try {
    if (ch.messageEncoding === "cdr") {
      if (schema.encoding !== "ros2msg") throw new Error(`cdr channel with schema encoding "${schema.encoding}"`);
      const msgReader = new MessageReader(parseMsgDef(schemaText, { ros2: true }));
      decoders.set(id, (data) => {
        if (data.length < 4 || data[0] !== 0 || data[1] !== 1 || data[2] !== 0 || data[3] !== 0) {
          throw new Error(`CDR encapsulation header is ${Buffer.from(data.subarray(0, 4)).toString("hex")}, expected 00010000`);
        }
        const msg = msgReader.readMessage(data);
        const trailing = data.length - msgReader.lastReadByteLength();
        if (trailing > 7) throw new Error(`${trailing} bytes left after decoding (schema mismatch?)`);
        return msg;
      });
    } else if (ch.messageEncoding === "json") {
      if (schema.encoding !== "jsonschema") throw new Error(`json channel with schema encoding "${schema.encoding}"`);
      const embedded = JSON.parse(schemaText);
      const validateEmbedded = ajvFor(embedded).compile(embedded);
      let validateOfficial;
      if (schema.name.startsWith("foxglove.")) {
        const official = foxgloveJsonSchemas[schema.name.slice("foxglove.".length)];
        if (!official || official.title !== schema.name) throw new Error(`no Foxglove JSON schema named ${schema.name}`);
        validateOfficial = new Ajv({ strict: false, allErrors: true }).compile(official);
      }
      decoders.set(id, (data) => {
        const msg = JSON.parse(new TextDecoder("utf-8", { fatal: true }).decode(data));
        if (!validateEmbedded(msg)) throw new Error(`violates the file's schema ${schema.name}: ${ajvErrors(validateEmbedded)}`);
        if (validateOfficial && !validateOfficial(msg)) {
          throw new Error(`violates Foxglove's ${schema.name}: ${ajvErrors(validateOfficial)}`);
        }
        return msg;
      });
    } else {
      throw new Error(`unsupported message encoding "${ch.messageEncoding}"`);
    }
  } catch (e) {
    fail(`${where} (schema ${schema.name}): ${e.message}`);
  }
}
bail();

// 2. Read and decode every message through the indexes.
const byTopic = new Map(); // topic -> [{logTime, msg}]
const indexedKeys = new Map(); // channel id -> [key]
const msgKey = (m) => `${m.logTime}:${m.publishTime}:${m.sequence}:${m.data.length}:${crc32(m.data)}`;
let total = 0;
try {
  for await (const m of reader.readMessages({ validateCrcs: true })) {
    total++;
    const ch = reader.channelsById.get(m.channelId);
    if (!ch) {
      fail(`message with unknown channel id ${m.channelId}`);
      continue;
    }
    const list = byTopic.get(ch.topic) ?? [];
    byTopic.set(ch.topic, list);
    if (!indexedKeys.has(m.channelId)) indexedKeys.set(m.channelId, []);
    indexedKeys.get(m.channelId).push(msgKey(m));
    let msg;
    try {
      msg = decoders.get(m.channelId)(m.data);
    } catch (e) {
      fail(`topic ${ch.topic} message #${list.length}: ${e.message}`);
    }
    list.push({ logTime: m.logTime, msg });
  }
} catch (e) {
  die(`McapIndexedReader.readMessages: ${e.message}`);
}
bail();
if (reader.statistics && reader.statistics.messageCount !== BigInt(total)) {
  fail(`statistics message_count ${reader.statistics.messageCount} != ${total} messages read`);
}

// 3. Stream the whole file (validateCrcs) and compare with the indexed read.
{
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  const streamKeys = new Map();
  let sawDataEnd = false;
  let sawFooter = false;
  try {
    const piece = 1 << 20;
    for (let off = 0; off < buf.length; off += piece) {
      stream.append(buf.subarray(off, Math.min(off + piece, buf.length)));
      let rec;
      while ((rec = stream.nextRecord())) {
        if (rec.type === "Message") {
          if (!streamKeys.has(rec.channelId)) streamKeys.set(rec.channelId, []);
          streamKeys.get(rec.channelId).push(msgKey(rec));
        } else if (rec.type === "DataEnd") {
          sawDataEnd = true;
        } else if (rec.type === "Footer") {
          sawFooter = true;
        }
      }
    }
    if (!stream.done()) throw new Error(`stream not complete (${stream.bytesRemaining()} bytes left)`);
  } catch (e) {
    die(`McapStreamReader: ${e.message}`);
  }
  if (!sawDataEnd || !sawFooter) fail("stream: no DataEnd or Footer record");
  for (const id of new Set([...streamKeys.keys(), ...indexedKeys.keys()])) {
    const a = [...(streamKeys.get(id) ?? [])].sort();
    const b = [...(indexedKeys.get(id) ?? [])].sort();
    const topic = reader.channelsById.get(id)?.topic ?? `channel ${id}`;
    if (a.length !== b.length || a.some((k, i) => k !== b[i])) {
      fail(`topic ${topic}: streamed messages (${a.length}) differ from the indexed ones (${b.length})`);
    }
  }
}
if (dataCrcError) die();
bail();

// 4. Content checks against trajectories.csv.
const msgs = (topic) => byTopic.get(topic) ?? [];
const distinctT = new Set(rows.map((r) => tNs(r.t)));
const rowsOf = agents.map(() => []);
for (const r of rows) {
  if (r.agent >= agents.length) die(`csv line ${r.line}: agent ${r.agent} but metadata lists ${agents.length} agents`);
  rowsOf[r.agent].push(r);
}
const rowAt = agents.map((_, k) => new Map(rowsOf[k].map((r) => [tNs(r.t), r])));
rowsOf.forEach((list, k) => {
  if (rowAt[k].size !== list.length) fail(`csv: agent ${k} has repeated t values`);
});
bail();

agents.forEach((ns, k) => {
  const want = rowsOf[k];
  const odom = msgs(`/${ns}/odom`);
  const cmd = msgs(`/${ns}/cmd_vel`);
  if (odom.length !== want.length) fail(`/${ns}/odom has ${odom.length} messages, csv has ${want.length} rows for agent ${k}`);
  if (cmd.length !== want.length) fail(`/${ns}/cmd_vel has ${cmd.length} messages, csv has ${want.length} rows for agent ${k}`);
  odom.forEach(({ msg }, i) => {
    const where = `topic /${ns}/odom message #${i}`;
    const row = want[i];
    if (!row) return;
    const s = stampNs(msg.header.stamp);
    if (s !== tNs(row.t)) {
      fail(`${where}: stamp ${s} ns != round(t*1e9) ${tNs(row.t)} of csv line ${row.line}`);
      return;
    }
    const p = msg.pose.pose.position;
    const q = msg.pose.pose.orientation;
    const yaw = yawOf(q);
    const bad = [];
    if (msg.header.frame_id !== "world") bad.push(`frame_id "${msg.header.frame_id}" != "world"`);
    if (msg.child_frame_id !== `${ns}/base_link`) bad.push(`child_frame_id "${msg.child_frame_id}" != "${ns}/base_link"`);
    if (!near(p.x, row.x)) bad.push(`x ${p.x} != ${row.x}`);
    if (!near(p.y, row.y)) bad.push(`y ${p.y} != ${row.y}`);
    if (!near(p.z, 0)) bad.push(`z ${p.z} != 0`);
    if (!near(q.x, 0) || !near(q.y, 0)) bad.push(`orientation not about +z (x=${q.x}, y=${q.y})`);
    if (!(angleDiff(yaw, row.heading) <= TOL)) bad.push(`yaw ${yaw} != heading ${row.heading} (mod 2pi)`);
    if (!near(msg.twist.twist.linear.x, row.v)) bad.push(`twist.linear.x ${msg.twist.twist.linear.x} != v ${row.v}`);
    if (bad.length) fail(`${where} (csv line ${row.line}): ${bad.join("; ")}`);
  });

  const img = msgs(`/${ns}/camera/image/compressed`);
  const info = msgs(`/${ns}/camera/camera_info`);
  if (img.length !== info.length) fail(`/${ns}/camera/image/compressed has ${img.length} messages, camera_info ${info.length}`);
  if (img.length > want.length) fail(`/${ns}/camera/image/compressed has ${img.length} messages, more than the ${want.length} rows`);
  img.forEach(({ msg }, i) => {
    const where = `topic /${ns}/camera/image/compressed message #${i}`;
    const d = msg.data;
    if (d.length < 8 || PNG_MAGIC.some((b, j) => d[j] !== b)) fail(`${where}: data does not start with the PNG magic`);
    if (msg.format !== "png") fail(`${where}: format "${msg.format}" != "png"`);
    if (msg.header.frame_id !== `${ns}/camera_optical`) fail(`${where}: frame_id "${msg.header.frame_id}" != "${ns}/camera_optical"`);
    const ci = info[i]?.msg;
    if (ci && stampNs(ci.header.stamp) !== stampNs(msg.header.stamp)) {
      fail(`${where}: stamp ${stampNs(msg.header.stamp)} != camera_info #${i}'s ${stampNs(ci.header.stamp)}`);
    }
  });
});

if (msgs("/tf").length !== distinctT.size) fail(`/tf has ${msgs("/tf").length} messages, csv has ${distinctT.size} distinct t`);
if (msgs("/world").length !== distinctT.size) fail(`/world has ${msgs("/world").length} messages, csv has ${distinctT.size} distinct t`);
msgs("/tf").forEach(({ msg }, i) => {
  for (const tr of msg.transforms) {
    const k = agents.findIndex((ns) => tr.child_frame_id === `${ns}/base_link`);
    const where = `topic /tf message #${i} (${tr.header.frame_id} -> ${tr.child_frame_id})`;
    if (k < 0) continue;
    const row = rowAt[k].get(stampNs(tr.header.stamp));
    if (!row) {
      fail(`${where}: no csv row for agent ${k} at stamp ${stampNs(tr.header.stamp)}`);
      continue;
    }
    const { translation: p, rotation: q } = tr.transform;
    if (tr.header.frame_id !== "world" || !near(p.x, row.x) || !near(p.y, row.y) || !(angleDiff(yawOf(q), row.heading) <= TOL)) {
      fail(`${where}: pose (${p.x}, ${p.y}, yaw ${yawOf(q)}) in "${tr.header.frame_id}" != csv line ${row.line}`);
    }
  }
});
const tfStatic = msgs("/tf_static");
if (tfStatic.length < 1) fail("/tf_static has no message");
const staticChildren = new Set(tfStatic.flatMap(({ msg }) => msg.transforms.map((t) => `${t.header.frame_id} -> ${t.child_frame_id}`)));
for (const ns of agents) {
  if (!staticChildren.has(`${ns}/base_link -> ${ns}/camera_optical`)) fail(`/tf_static lacks ${ns}/base_link -> ${ns}/camera_optical`);
}
bail();

const counts = {};
for (const topic of [...byTopic.keys()].sort()) counts[topic] = byTopic.get(topic).length;
console.log(JSON.stringify(counts, null, 1));
console.log("ok");
