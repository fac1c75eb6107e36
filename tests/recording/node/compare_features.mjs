#!/usr/bin/env node
// Compares what `flowsteer replay` found in a recording (its features.csv) with what the
// simulated agent found in the same frames (its /NS/step messages in the simulation's MCAP).
// usage: node compare_features.mjs SIM.mcap NAMESPACE FEATURES.csv
// Frames are matched by time (ms); in each frame the objects by label. Prints the counts and the
// largest differences; exits 1 when a frame's objects differ in number, status or label, or a
// centre, FOE or TTC differs by more than the tolerances below.
import { readFileSync } from "node:fs";
import { McapIndexedReader } from "@mcap/core";
import { loadDecompressHandlers } from "@mcap/support";

// The replay sees the same pixels (PNG is lossless), speed, turn rate and mount as the agent, and
// both print their numbers exactly: a feature may differ only by float rounding.
const TOL = { centre: 1e-9, foe: 1e-9, ttc_rel: 1e-9 };

const [, , simPath, ns, csvPath] = process.argv;
if (!simPath || !ns || !csvPath) {
  console.error("usage: node compare_features.mjs SIM.mcap NAMESPACE FEATURES.csv");
  process.exit(2);
}

function fileReadable(path) {
  const bytes = readFileSync(path);
  return {
    size: async () => BigInt(bytes.byteLength),
    read: async (offset, length) => bytes.subarray(Number(offset), Number(offset + length)),
  };
}

const frameKey = (tSeconds) => Math.round(tSeconds * 1000);
const sim = new Map();
const reader = await McapIndexedReader.Initialize({
  readable: fileReadable(simPath),
  decompressHandlers: await loadDecompressHandlers(),
});
for await (const m of reader.readMessages({ topics: [`/${ns}/step`] })) {
  const step = JSON.parse(new TextDecoder().decode(m.data));
  sim.set(frameKey(step.timestamp.sec + step.timestamp.nsec * 1e-9), step);
}

const lines = readFileSync(csvPath, "utf8").split(/\r?\n/).filter((l) => l.trim() !== "");
const header = lines[0].split(",");
const col = Object.fromEntries(header.map((name, i) => [name, i]));
const replay = new Map();
for (const line of lines.slice(1)) {
  const cells = line.split(",");
  const key = frameKey(Number(cells[col.t_s]));
  const num = (name) => (cells[col[name]] === "" ? null : Number(cells[col[name]]));
  if (!replay.has(key)) replay.set(key, []);
  replay.get(key).push({
    status: cells[col.status], label: num("label"), centre_x: num("centre_x"),
    centre_y: num("centre_y"), foe_x: num("foe_x"), foe_y: num("foe_y"), ttc_s: num("ttc_s"),
  });
}

const errors = [];
let compared = 0;
let objects = 0;
const worst = { centre: 0, foe: 0, ttc_rel: 0 };
for (const [key, step] of sim) {
  const found = replay.get(key) ?? [];
  compared += 1;
  if (found.length !== step.objects.length) {
    errors.push(`t = ${key} ms: the agent saw ${step.objects.length} objects, the replay ${found.length}`);
    continue;
  }
  for (const o of step.objects) {
    const r = found.find((x) => x.label === o.label);
    if (!r || r.status !== o.status) {
      errors.push(`t = ${key} ms: object ${o.label} (${o.status}) is ${r ? r.status : "missing"} in the replay`);
      continue;
    }
    objects += 1;
    const diff = (a, b) => (a === null && b === null ? 0 : a === null || b === null ? Infinity : Math.abs(a - b));
    worst.centre = Math.max(worst.centre, diff(o.centre_x, r.centre_x), diff(o.centre_y, r.centre_y));
    worst.foe = Math.max(worst.foe, diff(o.foe_x, r.foe_x), diff(o.foe_y, r.foe_y));
    if (o.ttc_s !== null || r.ttc_s !== null) {
      worst.ttc_rel = Math.max(worst.ttc_rel, diff(o.ttc_s, r.ttc_s) / Math.max(1, Math.abs(o.ttc_s ?? 0)));
    }
  }
}
if (compared === 0) errors.push(`${simPath}: no /${ns}/step messages`);
for (const k of Object.keys(TOL)) {
  if (!(worst[k] <= TOL[k])) errors.push(`largest ${k} difference ${worst[k]} > ${TOL[k]}`);
}
console.log(JSON.stringify({ frames: compared, objects, largest_difference: worst }));
if (errors.length > 0) {
  for (const e of errors.slice(0, 20)) console.error(`compare_features: FAIL: ${e}`);
  process.exit(1);
}
console.log("ok");
