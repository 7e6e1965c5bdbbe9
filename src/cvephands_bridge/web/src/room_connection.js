// The browser side of the room protocol (include/cvephands_bridge/room/room_protocol.h): joins a
// room as a viewer (no seat, never sends hands), follows the membership, measures the clock
// offset to the server with pings and hands every relayed binary frame to a callback.
// Reconnects on its own unless the server refused us for good (bad token, bad join), backing
// off exponentially (retryDelayMs) so that a room server that restarts is not hammered by every
// open page.

export const RELAY_HEADER_SIZE = 32;
const RELAY_MAGIC = [0x43, 0x56, 0x52, 0x4d]; // "CVRM"
const FATAL_REASONS = new Set(['bad_token', 'bad_join', 'malformed', 'unknown_type']);

// Wait before reconnect attempt `failures` (1 = after the first failure): 1 s, 2 s, 4 s, ...
// up to 30 s; a successful join starts again at 1 s. The same as the rigs' bridge
// (include/cvephands_bridge/room/reconnect_backoff.h), and deterministic like it.
export function retryDelayMs(failures, initialMs = 1000, maxMs = 30000) {
  return Math.min(maxMs, initialMs * 2 ** Math.max(0, Math.min(failures - 1, 30)));
}

// Wall clock in milliseconds since the Unix epoch with sub-millisecond resolution.
export function nowMs() {
  return performance.timeOrigin + performance.now();
}

// The 32-byte relay header in front of every binary frame from the server, or null when the
// frame is not one (wrong magic or version, header larger than the frame).
export function parseRelayHeader(buffer) {
  if (buffer.byteLength < RELAY_HEADER_SIZE) return null;
  const v = new DataView(buffer);
  for (let i = 0; i < 4; ++i) if (v.getUint8(i) !== RELAY_MAGIC[i]) return null;
  if (v.getUint8(4) !== 1) return null;
  const headerSize = v.getUint8(5);
  if (headerSize < RELAY_HEADER_SIZE || headerSize > buffer.byteLength) return null;
  const lo = v.getUint32(24, true);
  const hi = v.getUint32(28, true);
  return {
    sender: v.getUint32(8, true),
    seat: v.getUint32(12, true),
    sequence: v.getUint32(16, true),
    serverTimeMs: (hi * 4294967296 + lo) / 1000,
    payload: new Uint8Array(buffer, headerSize),
  };
}

export class RoomConnection {
  // options: url (ws://host:port/ws), room, name, token; callbacks onState(state, detail),
  // onParticipants(list, selfId), onHand(relay, receivedMs), onClock(offsetMs, rttMs).
  constructor(options) {
    this.options = options;
    this.state = 'idle';
    this.detail = '';
    this.selfId = 0;
    this.participants = [];
    // Server clock minus ours (ms), from the ping with the smallest round trip of the last 10.
    this.clockOffsetMs = 0;
    this.rttMs = NaN;
    this.samples = [];
    this.ws = null;
    this.pingTimer = null;
    this.retryTimer = null;
    this.failures = 0; // connection attempts that ended without a join, in a row
    this.pingId = 0;
    this.pending = new Map();
    this.stopped = false;
  }

  start() {
    this.stopped = false;
    this.connect();
  }

  stop() {
    this.stopped = true;
    clearTimeout(this.retryTimer);
    clearInterval(this.pingTimer);
    if (this.ws) this.ws.close(1000, 'bye');
  }

  setState(state, detail = '') {
    this.state = state;
    this.detail = detail;
    if (this.options.onState) this.options.onState(state, detail);
  }

  connect() {
    this.setState('connecting', this.options.url);
    let ws;
    try {
      ws = new WebSocket(this.options.url);
    } catch (e) {
      this.setState('error', String(e));
      return;
    }
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    let fatal = false;
    ws.onopen = () => {
      ws.send(JSON.stringify({
        type: 'join', room: this.options.room, name: this.options.name,
        token: this.options.token || '', role: 'viewer',
      }));
    };
    ws.onmessage = (ev) => {
      if (typeof ev.data !== 'string') {
        const relay = parseRelayHeader(ev.data);
        if (relay && this.options.onHand) this.options.onHand(relay, nowMs());
        return;
      }
      let msg;
      try {
        msg = JSON.parse(ev.data);
      } catch {
        return;
      }
      if (msg.type === 'welcome') {
        this.selfId = msg.participant;
        this.failures = 0;
        this.setState('joined', `room ${msg.room}`);
        this.ping();
        clearInterval(this.pingTimer);
        this.pingTimer = setInterval(() => this.ping(), 1000);
      } else if (msg.type === 'participants') {
        this.participants = msg.list || [];
        if (this.options.onParticipants) this.options.onParticipants(this.participants, this.selfId);
      } else if (msg.type === 'pong') {
        this.onPong(msg);
      } else if (msg.type === 'error') {
        fatal = FATAL_REASONS.has(msg.reason);
        this.setState('error', `${msg.reason}: ${msg.detail}`);
      }
    };
    ws.onclose = (ev) => {
      const wasJoined = this.state === 'joined';
      clearInterval(this.pingTimer);
      this.participants = [];
      if (this.options.onParticipants) this.options.onParticipants([], 0);
      if (this.state !== 'error') this.setState('closed', ev.reason || `code ${ev.code}`);
      if (this.stopped || fatal) return;
      // A connection that was joined retries at once-ish (1 s); failed attempts back off.
      if (!wasJoined) this.failures += 1;
      this.retryTimer = setTimeout(() => this.connect(), retryDelayMs(Math.max(1, this.failures)));
    };
  }

  ping() {
    if (!this.ws || this.ws.readyState !== WebSocket.OPEN) return;
    const id = ++this.pingId;
    this.pending.set(id, nowMs());
    this.ws.send(JSON.stringify({ type: 'ping', id }));
  }

  onPong(msg) {
    const sent = this.pending.get(msg.id);
    if (sent === undefined) return;
    this.pending.delete(msg.id);
    const received = nowMs();
    const rtt = received - sent;
    this.samples.push({ rtt, offset: msg.server_time_us / 1000 - (sent + received) / 2 });
    if (this.samples.length > 10) this.samples.shift();
    const best = this.samples.reduce((a, b) => (b.rtt < a.rtt ? b : a));
    this.clockOffsetMs = best.offset;
    this.rttMs = rtt;
    if (this.options.onClock) this.options.onClock(this.clockOffsetMs, this.rttMs);
  }
}
