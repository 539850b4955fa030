// The console's live Foxglove view through a third-party client, for any topics: npm
// `@foxglove/ws-protocol`'s FoxgloveClient over `ws`, each message decoded as Foxglove does
// (protobuf with `protobufjs` from the schema the server advertises, a FileDescriptorSet; JSON
// parsed). Usage: node foxglove_watch.mjs ws://127.0.0.1:PORT TOPIC...
// Prints one JSON object a line on stdout (tests/backend/foxglove_live/test_fleet_interop.py
// reads them): "ready" (the advertised channels, once the topics are subscribed), then a
// "message" per message received ({topic, logTime, message}: the decoded message). Ends when
// its standard input closes, or after two minutes.
import wsProtocol from "@foxglove/ws-protocol"; // CommonJS: no named exports in Node
import protobuf from "protobufjs";
import descriptor from "protobufjs/ext/descriptor/index.js";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;
const [url, ...topics] = process.argv.slice(2);
if (!url || !topics.length) {
  console.error("usage: node foxglove_watch.mjs ws://host:port TOPIC...");
  process.exit(2);
}
const LIFETIME_MS = 120000;
const say = (event, body = {}) => console.log(JSON.stringify({ event, ...body }));
const fail = (message) => {
  say("error", { message });
  process.exit(1);
};
setTimeout(() => fail(`still running after ${LIFETIME_MS} ms`), LIFETIME_MS).unref();

const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL, "foxglove.sdk.v1"]);
const client = new FoxgloveClient({ ws });
const channels = new Map();
const advertised = new Promise((resolve) =>
  client.on("advertise", (list) => {
    for (const channel of list) channels.set(channel.id, channel);
    resolve();
  }),
);
client.on("error", (err) => fail(String(err)));
await Promise.race([advertised, new Promise((_, reject) => setTimeout(() => reject(new Error("no advertise in 5 s")), 5000))]);

function typeOf(channel) {
  const set = descriptor.FileDescriptorSet.decode(Buffer.from(channel.schema, "base64"));
  return protobuf.Root.fromDescriptor(set).lookupType(channel.schemaName);
}
const byTopic = new Map([...channels.values()].map((c) => [c.topic, c]));
const subscriptions = new Map(); // subscription id -> {channel, type}
client.on("message", ({ subscriptionId, timestamp, data }) => {
  const { channel, type } = subscriptions.get(subscriptionId);
  const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  const message = type
    ? type.toObject(type.decode(bytes), { longs: String, defaults: true })
    : JSON.parse(new TextDecoder().decode(bytes));
  say("message", { topic: channel.topic, logTime: timestamp.toString(), message });
});
for (const topic of topics) {
  const channel = byTopic.get(topic);
  if (!channel) fail(`not advertised: ${topic}`);
  const type = channel.encoding === "protobuf" ? typeOf(channel) : null;
  subscriptions.set(client.subscribe(channel.id), { channel, type });
}
say("ready", {
  protocol: ws.protocol,
  channels: [...channels.values()].map(({ topic, encoding, schemaName }) => ({ topic, encoding, schemaName })),
});

process.stdin.on("end", () => {
  client.close();
  process.exit(0);
});
process.stdin.resume();
