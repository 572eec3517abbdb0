// Reads an MCAP file with the ecosystem's own libraries, independently of the lab's C++ reader:
// @mcap/core (stream reader with CRC checks, and the indexed reader through the summary) and
// @foxglove/omgidl-serialization (CDR decoding against the IDL schema stored in the file).
// Prints one JSON line of totals, then one JSON line per message with its decoded value.
//   node check_mcap.mjs FILE
import fs from "node:fs";
import { McapStreamReader, McapIndexedReader } from "@mcap/core";
import { parseIDL } from "@foxglove/omgidl-parser";
import { MessageReader } from "@foxglove/omgidl-serialization";
import zstd from "@foxglove/wasm-zstd";
import lz4 from "@foxglove/wasm-lz4";

const file = process.argv[2];
const bytes = fs.readFileSync(file);
await zstd.isLoaded;
await lz4.isLoaded;
const decompressHandlers = {
  zstd: (buffer, size) => zstd.decompress(buffer, Number(size)),
  lz4: (buffer, size) => lz4(buffer, Number(size)),
};

// JSON has no BigInt: 64-bit integers become numbers (exact below 2^53, as the lab's are).
const plain = (v) =>
  typeof v === "bigint" ? Number(v)
  : Array.isArray(v) || ArrayBuffer.isView(v) ? Array.from(v, plain)
  : v && typeof v === "object" ? Object.fromEntries(Object.entries(v).map(([k, x]) => [k, plain(x)]))
  : v;

const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
stream.append(bytes);
const schemas = new Map(), channels = new Map(), readers = new Map(), counts = {};
const lines = [];
let record;
while ((record = stream.nextRecord())) {
  counts[record.type] = (counts[record.type] ?? 0) + 1;
  if (record.type === "Schema") schemas.set(record.id, record);
  else if (record.type === "Channel") channels.set(record.id, record);
  else if (record.type === "Message") {
    const channel = channels.get(record.channelId);
    const schema = schemas.get(channel.schemaId);
    if (!readers.has(schema.id)) {
      if (schema.encoding !== "omgidl") throw new Error(`schema ${schema.name}: encoding ${schema.encoding}`);
      const text = new TextDecoder().decode(schema.data);
      readers.set(schema.id, new MessageReader(schema.name, parseIDL(text)));
    }
    const message = readers.get(schema.id).readMessage(record.data);
    lines.push(JSON.stringify({ topic: channel.topic, schema: schema.name, encoding: channel.messageEncoding,
      sequence: record.sequence, log_time: Number(record.logTime), publish_time: Number(record.publishTime),
      message: plain(message) }));
  }
}
if (!stream.done()) throw new Error("the stream reader did not reach the end of the file");

// The same file through its summary and indexes.
const readable = {
  size: async () => BigInt(bytes.length),
  read: async (offset, size) => bytes.subarray(Number(offset), Number(offset + size)),
};
const indexed = await McapIndexedReader.Initialize({ readable, decompressHandlers });
let indexedMessages = 0;
for await (const _ of indexed.readMessages()) indexedMessages++;
const stats = indexed.statistics;
console.log(JSON.stringify({ records: counts, messages: lines.length, indexed_messages: indexedMessages,
  statistics_messages: stats ? Number(stats.messageCount) : -1, chunk_indexes: indexed.chunkIndexes.length,
  attachments: indexed.attachmentIndexes.length, metadata: indexed.metadataIndexes.length }));
for (const l of lines) console.log(l);
