// protocol.js: a Foxglove WebSocket protocol client (subprotocol foxglove.websocket.v1) for the
// page: serverInfo, advertise and status in, subscribe out, binary message data (opcode 1,
// uint32 subscription id, uint64 log time ns, little-endian, then a JSON message) decoded.
export const SUBPROTOCOL = "foxglove.websocket.v1";

export class FoxgloveConnection {
  // handlers: { onOpen(), onClose(reason), onStatus(level, message), onMessage(topic, message, bytes) }
  constructor(url, topics, handlers) {
    this.topics = new Set(topics);
    this.handlers = handlers;
    this.channels = new Map(); // channel id -> channel
    this.subscriptions = new Map(); // subscription id -> topic
    this.nextSubscription = 1;
    this.bytesReceived = 0;
    this.ws = new WebSocket(url, [SUBPROTOCOL]);
    this.ws.binaryType = "arraybuffer";
    this.decoder = new TextDecoder();
    this.ws.onopen = () => handlers.onOpen?.();
    this.ws.onclose = (event) => handlers.onClose?.(event.reason || `closed (${event.code})`);
    this.ws.onmessage = (event) => this.receive(event.data);
  }

  receive(data) {
    if (typeof data === "string") {
      this.bytesReceived += data.length;
      const message = JSON.parse(data);
      if (message.op === "advertise") {
        const wanted = [];
        for (const channel of message.channels) {
          this.channels.set(channel.id, channel);
          if (this.topics.has(channel.topic)) {
            const id = this.nextSubscription++;
            this.subscriptions.set(id, channel.topic);
            wanted.push({ id, channelId: channel.id });
          }
        }
        if (wanted.length > 0) this.ws.send(JSON.stringify({ op: "subscribe", subscriptions: wanted }));
      } else if (message.op === "status") {
        this.handlers.onStatus?.(message.level, message.message);
      } else if (message.op === "serverInfo") {
        this.serverInfo = message;
      }
      return;
    }
    this.bytesReceived += data.byteLength;
    const view = new DataView(data);
    if (view.getUint8(0) !== 1) return; // only message data is expected
    const subscription = view.getUint32(1, true);
    const topic = this.subscriptions.get(subscription);
    if (topic === undefined) return;
    const text = this.decoder.decode(new Uint8Array(data, 13));
    this.handlers.onMessage?.(topic, JSON.parse(text), data.byteLength);
  }

  close() {
    this.ws.close();
  }
}
