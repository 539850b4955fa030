// The console's live Foxglove view through a third-party client: npm `@foxglove/ws-protocol`'s
// FoxgloveClient over `ws`, decoding the protobuf messages with `protobufjs` from the schema
// the server advertises (a FileDescriptorSet), as Foxglove does.
// Usage: node foxglove_live.mjs ws://127.0.0.1:PORT MIN_MOVE_M
// Prints one JSON object a line on stdout (tests/backend/foxglove_live/test_interop.py reads
// them): "refused" (a client offering only the old subprotocol name), "ready" (server info,
// the advertised channels, the status answering a client advertise), then "pose", "command",
// "log" and "time" events, and "done" once the decoded poses have moved MIN_MOVE_M metres.
import wsProtocol from "@foxglove/ws-protocol"; // CommonJS: no named exports in Node
import protobuf from "protobufjs";
import descriptor from "protobufjs/ext/descriptor/index.js";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;
const [url, minMove] = [process.argv[2], Number(process.argv[3] ?? "2")];
if (!url) {
  console.error("usage: node foxglove_live.mjs ws://host:port [MIN_MOVE_M]");
  process.exit(2);
}
const say = (event, body = {}) => console.log(JSON.stringify({ event, ...body }));
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));
const withTimeout = (promise, ms, what) =>
  Promise.race([
    promise,
    sleep(ms).then(() => {
      throw new Error(`timed out after ${ms} ms: ${what}`);
    }),
  ]);

// 1. The protocol's first name only (what Lichtblick offered before it learnt the new one).
const refused = await withTimeout(
  new Promise((resolve) => {
    const old = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
    old.on("unexpected-response", (_req, res) => resolve({ status: res.statusCode }));
    old.on("open", () => {
      resolve({ status: 101, protocol: old.protocol });
      old.close();
    });
    old.on("error", (err) => resolve({ error: String(err) }));
  }),
  5000,
  "the old subprotocol's handshake",
);
say("refused", refused);

// 2. What the Foxglove app offers: both names; the server picks the one it speaks.
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL, "foxglove.sdk.v1"]);
const client = new FoxgloveClient({ ws });
const serverInfo = new Promise((resolve) => client.on("serverInfo", resolve));
const channels = new Map();
const advertised = new Promise((resolve) =>
  client.on("advertise", (list) => {
    for (const channel of list) channels.set(channel.id, channel);
    resolve();
  }),
);
const statuses = [];
client.on("status", (status) => statuses.push(status));
client.on("error", (err) => say("error", { message: String(err) }));
const info = await withTimeout(serverInfo, 5000, "serverInfo");
await withTimeout(advertised, 5000, "advertise");

function typeOf(channel) {
  if (channel.encoding !== "protobuf") return null;
  const set = descriptor.FileDescriptorSet.decode(Buffer.from(channel.schema, "base64"));
  return protobuf.Root.fromDescriptor(set).lookupType(channel.schemaName);
}
// Messages, decoded (listening before subscribing: what stays drawn comes at once).
const byTopic = new Map([...channels.values()].map((c) => [c.topic, c]));
const decoders = new Map();
const subscriptions = new Map();
let first = null;
let times = 0;
let moved;
const done = new Promise((resolve) => {
  moved = resolve;
});
client.on("time", ({ timestamp }) => {
  times += 1;
  if (times % 20 === 1) say("time", { ns: timestamp.toString() });
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const channel = subscriptions.get(subscriptionId);
  const logTime = timestamp.toString();
  const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  if (channel.encoding === "json") {
    say("command", { logTime, record: JSON.parse(new TextDecoder().decode(bytes)) });
    return;
  }
  const type = decoders.get(channel.id);
  const message = type.toObject(type.decode(bytes), { longs: String, defaults: true });
  if (channel.topic === "/log") {
    say("log", { logTime, level: message.level, text: message.message, name: message.name });
  } else if (channel.topic !== "/vehicle/pose") {
    const entities = message.entities.map((e) => e.id);
    say("scene", { topic: channel.topic, logTime, entities, deletions: message.deletions.length });
  } else {
    const { position, orientation } = message.pose;
    say("pose", { logTime, stamp: message.timestamp, frameId: message.frameId, position, orientation });
    first ??= position;
    if (Math.hypot(position.x - first.x, position.y - first.y) >= minMove) moved();
  }
});
for (const topic of ["/vehicle/pose", "/commands", "/log", "/paths/active", "/station"]) {
  const channel = byTopic.get(topic);
  if (!channel) throw new Error(`not advertised: ${topic}`);
  decoders.set(channel.id, typeOf(channel));
  subscriptions.set(client.subscribe(channel.id), channel);
}

// 3. A client may not publish: its advertise is answered with an error status.
const answered = new Promise((resolve) => client.on("status", resolve));
const mine = client.advertise({ topic: "/intruder", encoding: "json", schemaName: "x" });
const refusal = await withTimeout(answered, 5000, "the answer to a client advertise");
client.sendMessage(mine, new TextEncoder().encode('{"x":1}'));

say("ready", {
  protocol: ws.protocol,
  serverInfo: info,
  channels: [...channels.values()].map(({ id, topic, encoding, schemaName, schemaEncoding, schema }) => ({
    id,
    topic,
    encoding,
    schemaName,
    schemaEncoding,
    schema: encoding === "json" ? schema : null,
    decodes: encoding === "protobuf" ? typeOf({ encoding, schema, schemaName }) !== null : null,
  })),
  refusal,
});

// 4. Until the vehicle has moved.
await withTimeout(done, 60000, `poses moving ${minMove} m`);
say("done", { statuses, times });
client.close();
process.exit(0);
