// Reads a flight recording with the MCAP project's own TypeScript library (@mcap/core), as an
// independent check of our writer: node read_recording.mjs FILE prints one JSON object
//   {"channels": [{"topic", "message_encoding", "schema", "schema_encoding", "messages"}],
//    "messages", "metadata": [names], "summary": {"message_count", "channels", "schemas"}}
// after decoding every message: the JSON ones parsed and checked against their channel's
// JSON Schema (type object, every required key present), the x-staa-cycle ones by the
// documented header (docs/ARCHITECTURE.md, "Flight recorder": version 1, the agent of the
// channel's metadata, the cycle's time equal to the message's log time, a known step kind).
// Exit 0 read, 1 a failure (the reason on stderr), 77 @mcap/core is not installed
// (toolchain/install-deps.sh: npm ci in tests/mcap).
import { readFileSync } from "node:fs";

let mcap;
try {
  mcap = await import("@mcap/core");
} catch (e) {
  console.error(`read_recording: @mcap/core is not installed here (npm ci --prefix tests/mcap): ${e.message}`);
  process.exit(77);
}

function fail(message) {
  console.error(`read_recording: ${message}`);
  process.exit(1);
}

const file = process.argv[2];
if (!file) fail("usage: node read_recording.mjs FILE");
const bytes = readFileSync(file);
const text = new TextDecoder("utf-8", { fatal: true });

// 1. Every record, streamed.
const schemas = new Map();
const channels = new Map();
const counts = new Map();
const metadata = [];
let messages = 0;
const reader = new mcap.McapStreamReader({ validateCrcs: true });
reader.append(new Uint8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength));
for (let record; (record = reader.nextRecord()); ) {
  switch (record.type) {
    case "Schema":
      schemas.set(record.id, record);
      break;
    case "Channel":
      channels.set(record.id, record);
      break;
    case "Metadata":
      metadata.push(record.name);
      break;
    case "Message": {
      const channel = channels.get(record.channelId);
      if (!channel) fail(`a message on channel ${record.channelId}, which was not defined before it`);
      decode(channel, record);
      counts.set(channel.id, (counts.get(channel.id) ?? 0) + 1);
      ++messages;
      break;
    }
    default:
      break;
  }
}
if (!reader.done()) fail("the stream reader did not reach the footer and closing magic");

function decode(channel, message) {
  const where = `${channel.topic} message ${message.sequence}`;
  if (channel.messageEncoding === "json") {
    let value;
    try {
      value = JSON.parse(text.decode(message.data));
    } catch (e) {
      fail(`${where}: not JSON: ${e.message}`);
    }
    const schema = schemas.get(channel.schemaId);
    if (!schema || schema.encoding !== "jsonschema") fail(`${where}: its channel has no JSON Schema`);
    const rules = JSON.parse(text.decode(schema.data));
    if (rules.type === "object" && (typeof value !== "object" || value === null || Array.isArray(value))) {
      fail(`${where}: not an object`);
    }
    for (const key of rules.required ?? []) {
      if (!(key in value)) fail(`${where}: the required key '${key}' is missing`);
    }
  } else if (channel.messageEncoding === "x-staa-cycle") {
    const d = new DataView(message.data.buffer, message.data.byteOffset, message.data.byteLength);
    if (d.byteLength < 28) fail(`${where}: ${d.byteLength} bytes, shorter than the cycle header`);
    const version = d.getUint16(0, true);
    if (version !== 1) fail(`${where}: cycle encoding version ${version}`);
    const agent = d.getUint16(2, true);
    if (String(agent) !== channel.metadata.get("agent")) fail(`${where}: agent ${agent} on agent ${channel.metadata.get("agent")}'s channel`);
    const time = d.getBigInt64(12, true);
    if (BigInt.asUintN(64, time) !== message.logTime) fail(`${where}: cycle time ${time} but log time ${message.logTime}`);
    const step = d.getUint8(24);
    if (step > 2) fail(`${where}: step kind ${step}`);
  } else {
    fail(`${where}: unknown message encoding ${channel.messageEncoding}`);
  }
}

// 2. The summary, through the indexed reader (what Foxglove reads first).
const readable = {
  size: async () => BigInt(bytes.byteLength),
  read: async (offset, size) => new Uint8Array(bytes.buffer, bytes.byteOffset + Number(offset), Number(size)),
};
const indexed = await mcap.McapIndexedReader.Initialize({ readable });
const summary = {
  message_count: Number(indexed.statistics?.messageCount ?? -1),
  channels: indexed.channelsById.size,
  schemas: indexed.schemasById.size,
  metadata_index: indexed.metadataIndexes.length,
};
for (const [id, n] of indexed.statistics?.channelMessageCounts ?? []) {
  if (Number(n) !== (counts.get(id) ?? 0)) fail(`the statistics count ${n} messages on channel ${id}, the stream ${counts.get(id) ?? 0}`);
}

console.log(
  JSON.stringify({
    channels: [...channels.values()].map((c) => ({
      topic: c.topic,
      message_encoding: c.messageEncoding,
      schema: schemas.get(c.schemaId)?.name ?? null,
      schema_encoding: schemas.get(c.schemaId)?.encoding ?? null,
      messages: counts.get(c.id) ?? 0,
    })),
    messages,
    metadata,
    summary,
  }),
);
