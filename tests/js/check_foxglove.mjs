// An independent Foxglove client of the viewer (issue 72): @foxglove/ws-protocol's FoxgloveClient
// over `ws`, every advertised channel subscribed, every message decoded with
// @foxglove/omgidl-serialization against the schema the viewer advertised.
//   node check_foxglove.mjs ws://127.0.0.1:PORT [--seconds S] [--live N] [--stalled M]
// With --stalled, M more connections subscribe to everything and then never read (their socket
// paused). Prints one JSON line: per live client, per topic, messages decoded and errors.
import WebSocket from "ws";
import wsProtocol from "@foxglove/ws-protocol";
import { parseIDL } from "@foxglove/omgidl-parser";
import { MessageReader } from "@foxglove/omgidl-serialization";

const { FoxgloveClient } = wsProtocol;
const args = process.argv.slice(2);
const url = args[0];
const option = (name, fallback) => {
  const i = args.indexOf(name);
  return i >= 0 ? Number(args[i + 1]) : fallback;
};
const seconds = option("--seconds", 5), live = option("--live", 1), stalled = option("--stalled", 0);

function finite(value) {  // every number in a decoded message is finite
  if (typeof value === "number") return Number.isFinite(value);
  if (typeof value === "bigint" || typeof value === "string" || typeof value === "boolean") return true;
  if (value instanceof Uint8Array || Array.isArray(value)) return [...value].every(finite);
  if (value && typeof value === "object") return Object.values(value).every(finite);
  return true;
}

function liveClient() {
  const r = { subprotocol: "", server: "", channels: 0, topics: {}, errors: [], statuses: [] };
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  const client = new FoxgloveClient({ ws });
  const bySubscription = new Map();
  ws.on("open", () => { r.subprotocol = ws.protocol; });
  client.on("serverInfo", (info) => { r.server = info.name; });
  client.on("status", (s) => r.statuses.push(s.message));
  client.on("error", (e) => r.errors.push(String(e && e.message ? e.message : e)));
  client.on("advertise", (channels) => {
    for (const c of channels) {
      ++r.channels;
      if (c.encoding !== "cdr" || c.schemaEncoding !== "omgidl") {
        r.errors.push(`${c.topic}: encoding ${c.encoding}/${c.schemaEncoding}`);
        continue;
      }
      let reader;
      try {
        reader = new MessageReader(c.schemaName, parseIDL(c.schema));
      } catch (e) {
        r.errors.push(`${c.topic}: schema: ${e.message}`);
        continue;
      }
      bySubscription.set(client.subscribe(c.id), { topic: c.topic, reader });
      r.topics[c.topic] = { messages: 0, bad: 0, first_ns: null, last_ns: null };
    }
  });
  client.on("message", ({ subscriptionId, timestamp, data }) => {
    const s = bySubscription.get(subscriptionId);
    if (!s) return r.errors.push(`a message for unknown subscription ${subscriptionId}`);
    const t = r.topics[s.topic];
    try {
      const m = s.reader.readMessage(new Uint8Array(data.buffer, data.byteOffset, data.byteLength));
      if (!finite(m)) throw new Error("a non-finite number");
      ++t.messages;
      t.first_ns ??= String(timestamp);
      t.last_ns = String(timestamp);
    } catch (e) {
      ++t.bad;
      if (r.errors.length < 20) r.errors.push(`${s.topic}: ${e.message}`);
    }
  });
  return { r, close: () => client.close() };
}

function stalledClient() {
  const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
  ws.on("message", (data, binary) => {
    if (binary) return;
    const m = JSON.parse(data.toString());
    if (m.op !== "advertise") return;
    ws.send(JSON.stringify({ op: "subscribe", subscriptions: m.channels.map((c, i) => ({ id: i, channelId: c.id })) }));
    setTimeout(() => ws._socket.pause(), 100);  // from now on it never reads
  });
  ws.on("error", () => {});
  return { close: () => ws.terminate() };
}

const clients = Array.from({ length: live }, liveClient);
const stuck = Array.from({ length: stalled }, stalledClient);
await new Promise((resolve) => setTimeout(resolve, seconds * 1000));
console.log(JSON.stringify({ seconds, clients: clients.map((c) => c.r) }));
for (const c of clients) c.close();
for (const c of stuck) c.close();
process.exit(0);
