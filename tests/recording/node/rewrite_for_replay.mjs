#!/usr/bin/env node
// Independent writer: turns one agent of flowsteer's simulation recording into a robot-style
// recording (the topics a robot's rosbag2 would have) for `flowsteer replay` (see README.md).
// usage: node rewrite_for_replay.mjs SIM.mcap NAMESPACE OUT.mcap
//
// Reads with @mcap/core (decoding with the input's own schemas), writes with @mcap/core's McapWriter
// (zstd chunks, message indexes, summary, CRCs) and @foxglove/rosmsg2-serialization's MessageWriter,
// using the .msg definitions of ros2_msgs.mjs (not the input's schema texts).
import { open, readFile } from "node:fs/promises";
import { McapIndexedReader, McapWriter } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";
import { parse as parseMsgDef } from "@foxglove/rosmsg";
import { MessageReader, MessageWriter } from "@foxglove/rosmsg2-serialization";
import * as zstd from "@foxglove/wasm-zstd";
import { fullDefinition } from "./ros2_msgs.mjs";

function die(msg) {
  console.error(`rewrite_for_replay: ${msg}`);
  process.exit(1);
}

const [, , simPath, ns, outPath] = process.argv;
if (!simPath || !ns || !outPath) {
  console.error("usage: node rewrite_for_replay.mjs SIM.mcap NAMESPACE OUT.mcap");
  process.exit(2);
}

// ---------------------------------------------------------------------------- read the sim file
const buf = await readFile(simPath);
const reader = await McapIndexedReader.Initialize({
  readable: {
    size: async () => BigInt(buf.length),
    read: async (offset, size) => buf.subarray(Number(offset), Number(offset + size)),
  },
  decompressHandlers: await loadDecompressHandlers(),
}).catch((e) => die(`${simPath}: ${e.message}`));

for await (const m of reader.readMetadata({ name: "flowsteer" })) {
  const agents = JSON.parse(m.metadata.get("agents") ?? "null");
  if (Array.isArray(agents) && !agents.includes(ns)) die(`namespace "${ns}" is not one of the recording's agents ${JSON.stringify(agents)}`);
}

const topics = {
  odom: `/${ns}/odom`,
  image: `/${ns}/camera/image/compressed`,
  info: `/${ns}/camera/camera_info`,
  tfStatic: "/tf_static",
};
const readers = new Map(); // channel id -> MessageReader
for (const [id, ch] of reader.channelsById) {
  if (!Object.values(topics).includes(ch.topic)) continue;
  const schema = reader.schemasById.get(ch.schemaId);
  if (ch.messageEncoding !== "cdr" || schema?.encoding !== "ros2msg") die(`${ch.topic}: expected cdr/ros2msg`);
  readers.set(id, new MessageReader(parseMsgDef(new TextDecoder().decode(schema.data), { ros2: true })));
}
const present = new Set([...readers.keys()].map((id) => reader.channelsById.get(id).topic));
for (const t of Object.values(topics)) if (!present.has(t)) die(`${simPath} has no channel ${t}`);

const input = []; // {topic, logTime, publishTime, msg}
for await (const m of reader.readMessages({ topics: Object.values(topics), validateCrcs: true })) {
  const ch = reader.channelsById.get(m.channelId);
  input.push({ topic: ch.topic, logTime: m.logTime, publishTime: m.publishTime, msg: readers.get(m.channelId).readMessage(m.data) });
}

// ---------------------------------------------------------------------------- build the robot's messages
const OUT = {
  "/tf_static": { type: "tf2_msgs/msg/TFMessage", order: 0 },
  "/odom": { type: "nav_msgs/msg/Odometry", order: 1 },
  "/camera/camera_info": { type: "sensor_msgs/msg/CameraInfo", order: 2 },
  "/camera/image/compressed": { type: "sensor_msgs/msg/CompressedImage", order: 3 },
};
const stamp = (s) => ({ sec: s.sec, nanosec: s.nanosec });
const vec = (v) => ({ x: v.x, y: v.y, z: v.z });
const quat = (q) => ({ x: q.x, y: q.y, z: q.z, w: q.w });
const out = []; // {topic, logTime, publishTime, msg}
let staticTf;

for (const { topic, logTime, publishTime, msg } of input) {
  if (topic === topics.tfStatic) {
    const tr = msg.transforms.find((t) => t.header.frame_id === `${ns}/base_link` && t.child_frame_id === `${ns}/camera_optical`);
    if (tr && !staticTf) {
      staticTf = {
        topic: "/tf_static",
        logTime,
        publishTime,
        msg: {
          transforms: [{
            header: { stamp: stamp(tr.header.stamp), frame_id: "base_link" },
            child_frame_id: "camera_optical",
            transform: { translation: vec(tr.transform.translation), rotation: quat(tr.transform.rotation) },
          }],
        },
      };
      out.push(staticTf);
    }
  } else if (topic === topics.odom) {
    out.push({
      topic: "/odom",
      logTime,
      publishTime,
      msg: {
        header: { stamp: stamp(msg.header.stamp), frame_id: "odom" },
        child_frame_id: "base_link",
        pose: {
          pose: { position: vec(msg.pose.pose.position), orientation: quat(msg.pose.pose.orientation) },
          covariance: Array.from(msg.pose.covariance),
        },
        twist: {
          twist: { linear: vec(msg.twist.twist.linear), angular: vec(msg.twist.twist.angular) },
          covariance: Array.from(msg.twist.covariance),
        },
      },
    });
  } else if (topic === topics.image) {
    out.push({
      topic: "/camera/image/compressed",
      logTime,
      publishTime,
      msg: { header: { stamp: stamp(msg.header.stamp), frame_id: "camera_optical" }, format: msg.format, data: msg.data },
    });
  } else if (topic === topics.info) {
    out.push({
      topic: "/camera/camera_info",
      logTime,
      publishTime,
      msg: {
        header: { stamp: stamp(msg.header.stamp), frame_id: "camera_optical" },
        height: msg.height,
        width: msg.width,
        distortion_model: msg.distortion_model,
        d: Array.from(msg.d),
        k: Array.from(msg.k),
        r: Array.from(msg.r),
        p: Array.from(msg.p),
        binning_x: msg.binning_x,
        binning_y: msg.binning_y,
        roi: {
          x_offset: msg.roi.x_offset,
          y_offset: msg.roi.y_offset,
          height: msg.roi.height,
          width: msg.roi.width,
          do_rectify: msg.roi.do_rectify,
        },
      },
    });
  }
}
if (!staticTf) die(`/tf_static has no transform ${ns}/base_link -> ${ns}/camera_optical`);
const count = (t) => out.filter((o) => o.topic === t).length;
if (count("/camera/image/compressed") === 0) die(`${topics.image} has no messages (record the sim with --mcap-images K > 0)`);
if (count("/odom") === 0) die(`${topics.odom} has no messages`);

// Log-time order; at equal times: tf_static, odom, camera_info, image.
out.sort((a, b) => (a.logTime < b.logTime ? -1 : a.logTime > b.logTime ? 1 : OUT[a.topic].order - OUT[b.topic].order));

// ---------------------------------------------------------------------------- write
await zstd.isLoaded;
const fh = await open(outPath, "w");
let position = 0n;
const writer = new McapWriter({
  writable: {
    write: async (data) => {
      await fh.write(data);
      position += BigInt(data.byteLength);
    },
    position: () => position,
  },
  chunkSize: 1024 * 1024,
  compressChunk: (data) => ({ compression: "zstd", compressedData: new Uint8Array(zstd.compress(data, 3)) }),
});
await writer.start({ profile: "ros2", library: "flowsteer tests/recording/node/rewrite_for_replay.mjs" });
await writer.addMetadata({
  name: "rewrite_for_replay",
  metadata: new Map([["source", simPath], ["namespace", ns]]),
});
const channels = new Map();
for (const [topic, { type }] of Object.entries(OUT)) {
  const text = fullDefinition(type);
  const schemaId = await writer.registerSchema({ name: type, encoding: "ros2msg", data: new TextEncoder().encode(text) });
  const channelId = await writer.registerChannel({ topic, schemaId, messageEncoding: "cdr", metadata: new Map() });
  channels.set(topic, { channelId, msgWriter: new MessageWriter(parseMsgDef(text, { ros2: true })), sequence: 0 });
}
for (const o of out) {
  const ch = channels.get(o.topic);
  await writer.addMessage({
    channelId: ch.channelId,
    sequence: ch.sequence++,
    logTime: o.logTime,
    publishTime: o.publishTime,
    data: ch.msgWriter.writeMessage(o.msg),
  });
}
await writer.end();
await fh.close();

const counts = {};
for (const topic of Object.keys(OUT)) counts[topic] = count(topic);
console.log(JSON.stringify(counts));
