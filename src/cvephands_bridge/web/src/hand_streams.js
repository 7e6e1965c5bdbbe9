// Hands relayed by the room server: one codec decoder per sender (delta frames refer to that
// sender's previous frames) and the counters the page shows (messages, bytes, losses, decode
// errors). Every message is decoded (the next delta frame needs it), but only the newest frame
// of each hand is meshed (mesh()), so a page that renders slower than the rigs send keeps up.
import { HandStreamDecoder } from './hand_decoder.js';
import { keepHandComponents } from './mesh_components.js';
import { marchingCubes } from './marching_cubes.js';
import { nowMs } from './room_connection.js';

// What HandMesher drops (config/hand_mesher.yaml min_component_triangles, keep_radius).
const MIN_COMPONENT_TRIANGLES = 64;
const KEEP_RADIUS = 0.08;

export class HandStreams {
  constructor() {
    this.senders = new Map();
    this.latest = new Map(); // "sender/target" -> decoded frame not meshed yet
  }

  sender(id) {
    let s = this.senders.get(id);
    if (!s) {
      s = { decoder: new HandStreamDecoder(), lastSequence: -1, messages: 0, bytes: 0, missed: 0,
        errors: 0, waiting: 0, superseded: 0, lastError: '', faces: 0, badFaces: 0 };
      this.senders.set(id, s);
    }
    return s;
  }

  forget(keepIds) {
    for (const id of this.senders.keys()) if (!keepIds.has(id)) this.senders.delete(id);
  }

  // Every relayed message of a sender (hands and face pictures): the server's per-sender count
  // shows what it dropped for us (a slow reader).
  noteSequence(relay) {
    const s = this.sender(relay.sender);
    // Forward gaps only (mod 2^32): a repeated or older sequence is no loss.
    const gap = (relay.sequence - s.lastSequence - 1) >>> 0;
    if (s.lastSequence >= 0 && gap < 0x80000000) s.missed += gap;
    s.lastSequence = relay.sequence;
    return s;
  }

  // Decodes one relayed hand message; false for a bad or undecodable one (counted on the sender).
  decode(relay) {
    const s = this.sender(relay.sender);
    ++s.messages;
    s.bytes += relay.payload.byteLength;
    const t0 = nowMs();
    const r = s.decoder.decode(relay.payload);
    if (!r.ok) {
      // A delta frame before the first key frame (we joined mid-stream, or the server dropped
      // its reference for us) is expected: the rig sends a key frame when we join.
      if (r.reason.startsWith('missing reference')) ++s.waiting;
      else {
        ++s.errors;
        s.lastError = r.reason;
      }
      return false;
    }
    const key = `${relay.sender}/${r.frame.targetId}`;
    if (this.latest.has(key)) ++s.superseded;
    this.latest.set(key, { sender: relay.sender, frame: r.frame, serverMs: relay.serverTimeMs,
      decodeMs: nowMs() - t0 });
    return true;
  }

  // Meshes the newest frame of every hand decoded since the last call.
  mesh() {
    const out = [];
    for (const h of this.latest.values()) {
      const f = h.frame;
      const t0 = nowMs();
      const centre = [0, 1, 2].map((k) => f.origin[k] + 0.5 * f.voxelSize * f.dims[k]);
      const mesh = keepHandComponents(marchingCubes(
        { data: f.data, dims: f.dims, origin: f.origin, voxelSize: f.voxelSize },
        { iso: f.isoByte + 0.5, computeNormals: true },
      ), MIN_COMPONENT_TRIANGLES, centre, KEEP_RADIUS);
      out.push({ sender: h.sender, target: f.targetId, mesh,
        stampMs: f.stampSec * 1000 + f.stampNsec / 1e6, serverMs: h.serverMs,
        decodeMs: h.decodeMs, meshMs: nowMs() - t0 });
    }
    this.latest.clear();
    return out;
  }

  stats() {
    const o = {};
    for (const [id, s] of this.senders) {
      o[id] = { messages: s.messages, bytes: s.bytes, missed: s.missed, errors: s.errors,
        waiting: s.waiting, superseded: s.superseded, lastError: s.lastError, faces: s.faces,
        badFaces: s.badFaces };
    }
    return o;
  }
}
