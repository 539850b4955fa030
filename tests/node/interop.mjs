// roslibjs (npm `roslib` 2.x, Node with `ws`) against a rosbridge server: what a browser
// console would do. Usage: node interop.mjs ws://127.0.0.1:PORT FRAME_HEX
// Prints one JSON object of results on stdout; tests/rosbridge/test_roslibjs.py checks it.
import { Ros, Topic } from "roslib";

const [url, frameHex] = process.argv.slice(2);
if (!url || !frameHex) {
  console.error("usage: node interop.mjs ws://host:port FRAME_HEX");
  process.exit(2);
}
const frame = Array.from(Buffer.from(frameHex, "hex"));
const sleep = (ms) => new Promise((resolve) => setTimeout(resolve, ms));
const withTimeout = (promise, ms, what) =>
  Promise.race([
    promise,
    sleep(ms).then(() => {
      throw new Error(`timed out after ${ms} ms: ${what}`);
    }),
  ]);

const ros = new Ros({ url });
await withTimeout(new Promise((resolve, reject) => {
  ros.on("connection", resolve);
  ros.on("error", reject);
}), 5000, "connection");

const results = {};

// rosapi through roslibjs's own calls (relative names: "rosapi/topics", "rosapi/topic_type").
const listing = await withTimeout(
  new Promise((resolve, reject) => ros.getTopics(resolve, reject)),
  3000,
  "getTopics",
);
results.topics = listing.topics;
results.types = listing.types;
results.poseType = await withTimeout(
  new Promise((resolve, reject) => ros.getTopicType("/nemesys/pose", resolve, reject)),
  3000,
  "getTopicType",
);

// The frame echo and the acknowledgement of a published frame.
const echo = new Promise((resolve) => {
  const echoes = new Topic({ ros, name: "/nemesys/frame", messageType: "std_msgs/UInt8MultiArray" });
  echoes.subscribe((message) => resolve(message));
});
const ack = new Promise((resolve) => {
  const missions = new Topic({ ros, name: "/nemesys/mission", messageType: "std_msgs/String" });
  missions.subscribe((message) => resolve(JSON.parse(message.data)));
});
// Poses throttled to one a second, counted over 3 s.
let poses = 0;
const pose = new Topic({
  ros,
  name: "/nemesys/pose",
  messageType: "geometry_msgs/msg/PoseStamped",
  throttle_rate: 1000,
});
pose.subscribe(() => {
  poses += 1;
});
const frames = new Topic({ ros, name: "/nemesys/frame", messageType: "std_msgs/UInt8MultiArray" });
frames.advertise();
frames.publish({ data: frame });

const echoed = await withTimeout(echo, 3000, "frame echo");
results.echoDataType = typeof echoed.data;
results.echoData = echoed.data;
const acknowledgement = await withTimeout(ack, 5000, "acknowledgement");
results.ackOutcome = acknowledgement.outcome;
results.ackFrameHex = acknowledgement.frame_hex;

await sleep(3000);
results.posesIn3s = poses;
pose.unsubscribe();

// Foxglove's (Lichtblick's) rosbridge player: full definitions, then cbor-raw (roslibjs
// decodes the binary CBOR frame; msg.bytes is the CDR), and cbor for comparison. One client
// has one stream per topic, so each comes after the last one's unsubscribe.
const raw = await withTimeout(
  new Promise((resolve, reject) => ros.getTopicsAndRawTypes(resolve, reject)),
  3000,
  "getTopicsAndRawTypes",
);
results.rawTypes = raw;
const firstOf = (compression) =>
  withTimeout(
    new Promise((resolve) => {
      const topic = new Topic({ ros, name: "/nemesys/pose", compression });
      topic.subscribe((message) => {
        topic.unsubscribe();
        resolve(message);
      });
    }),
    3000,
    `${compression} pose`,
  );
const rawPose = await firstOf("cbor-raw");
results.cborRaw = {
  bytesIsUint8Array: rawPose.bytes instanceof Uint8Array,
  hex: Buffer.from(rawPose.bytes).toString("hex"),
  secs: rawPose.secs,
  nsecs: rawPose.nsecs,
};
results.cborPose = await firstOf("cbor");

// Fragments: a service response split with fragment_size 40 is reassembled by roslibjs
// (its id is the call's); a topic message fragmented by the server has id 0, which roslibjs
// ignores. fragment_size stays set for this connection, so this part comes last.
const fragmented = new Promise((resolve) => ros.once("frag-1", resolve));
ros.callOnConnection({ op: "call_service", id: "frag-1", service: "/rosapi/topics", fragment_size: 40 });
const reply = await withTimeout(fragmented, 3000, "fragmented service response");
results.fragmentedTopics = reply.values.topics;
let statuses = 0;
new Topic({ ros, name: "/nemesys/status", messageType: "std_msgs/String" }).subscribe(() => {
  statuses += 1;
});
await sleep(1200);
results.fragmentedStatusesIn1s = statuses;

frames.unadvertise();
ros.close();
console.log(JSON.stringify(results));
process.exit(0);
