// An independent Foxglove WebSocket client for REI's tests (tests/views/test_foxglove.py):
// Foxglove's own protocol client (@foxglove/ws-protocol) on the `ws` WebSocket, asking for
// the `foxglove.sdk.v1` subprotocol, and Foxglove's own ROS 2 decoders (@foxglove/rosmsg,
// @foxglove/rosmsg2-serialization). It subscribes to every channel the server advertises,
// decodes each message by its channel's schema and prints one JSON line per message:
// {"topic", "schema", "encoding", "logTime", "message"}. It ends when the server closes.
// With IDLE_MS, it also ends after IDLE_MS milliseconds without a message (so a test that
// waits for messages that never come fails instead of hanging).
// Usage: node client.mjs ws://127.0.0.1:PORT [IDLE_MS]
import wsProtocol from "@foxglove/ws-protocol";
import rosmsg from "@foxglove/rosmsg";
import serialization from "@foxglove/rosmsg2-serialization";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol; // CommonJS packages: their exports via the default
const { parse } = rosmsg;
const { MessageReader } = serialization;
const url = process.argv[2];
const idleMs = process.argv[3] ? Number(process.argv[3]) : 0;
let idle = null;
// process.exit drops the lines a full stdout pipe has not taken yet (a reader slower than the
// messages, as on a loaded machine: the test then read a line cut short): exit only once
// everything written before has gone out.
function finish() {
  process.stdout.write("", () => process.exit(0));
}
function stillHere() {
  if (idleMs > 0) {
    clearTimeout(idle);
    idle = setTimeout(finish, idleMs);
  }
}
const ws = new WebSocket(url, ["foxglove.sdk.v1"]);
const client = new FoxgloveClient({ ws });
const channels = new Map(); // subscription id -> { channel, decode }
const textDecoder = new TextDecoder();

function plain(value) {
  // typed arrays and bigints as JSON can carry them
  if (typeof value === "bigint") return Number(value);
  if (ArrayBuffer.isView(value)) return Array.from(value, plain);
  if (Array.isArray(value)) return value.map(plain);
  if (value !== null && typeof value === "object") {
    return Object.fromEntries(Object.entries(value).map(([k, v]) => [k, plain(v)]));
  }
  return value;
}

function decoder(channel) {
  if (channel.encoding === "cdr" && channel.schemaEncoding === "ros2msg") {
    const reader = new MessageReader(parse(channel.schema, { ros2: true }));
    return (data) => reader.readMessage(data);
  }
  if (channel.encoding === "json") {
    return (data) => JSON.parse(textDecoder.decode(data));
  }
  throw new Error(`no decoder for ${channel.topic}: ${channel.encoding}/${channel.schemaEncoding}`);
}

client.on("open", stillHere);
client.on("advertise", (advertised) => {
  for (const channel of advertised) {
    const id = client.subscribe(channel.id);
    channels.set(id, { channel, decode: decoder(channel) });
  }
});
client.on("message", ({ subscriptionId, timestamp, data }) => {
  stillHere();
  const { channel, decode } = channels.get(subscriptionId);
  const bytes = new Uint8Array(data.buffer, data.byteOffset, data.byteLength);
  process.stdout.write(JSON.stringify({
    topic: channel.topic, schema: channel.schemaName, encoding: channel.encoding,
    logTime: timestamp.toString(), message: plain(decode(bytes)),
  }) + "\n");
});
client.on("error", (error) => {
  process.stderr.write(`client error: ${error}\n`);
});
client.on("close", finish);
