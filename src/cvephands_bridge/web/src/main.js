// The room client page: joins the room given in the URL as a viewer and draws every rig's hands
// at its seat around the table, with the connection state, the participants, the render rate and
// the end-to-end latency (capture stamp -> first render of that frame's mesh). Each rig's
// user's face, when the rig sends it, shows on a video plane at its seat (thesis 7.5).
//
// URL parameters (all optional):
//   room    room to join (default "tabletop", the CveBridge default)
//   name    display name (default "browser")
//   token   the server's shared token, if it has one
//   server  WebSocket URL (default: /ws on the server that served this page)
//   seat    look from that seat's user's eyes instead of the overview
//   aa      0: no antialiasing (for software WebGL, e.g. headless Chromium's SwiftShader)
import * as THREE from 'three';
import { nowMs } from './room_connection.js';
import { RoomScene } from './room_scene.js';
const params = new URLSearchParams(window.location.search);
const wsDefault = `${window.location.protocol === 'https:' ? 'wss' : 'ws'}://${window.location.host}/ws`;
const options = {
  url: params.get('server') || wsDefault,
  room: params.get('room') || 'tabletop',
  name: params.get('name') || 'browser',
  token: params.get('token') || '',
};
const seatView = params.has('seat') ? Number(params.get('seat')) : null;
const HAND_TIMEOUT_MS = 500; // a hand not updated for this long is gone (DESIGN: loss <= 0.5 s)
const WINDOW_MS = 3000;       // statistics over the last 3 s

// Samples of the last WINDOW_MS with their median and 95th percentile.
class Window {
  constructor() { this.items = []; }
  push(t, v) { this.items.push([t, v]); }
  trim(now) {
    let i = 0;
    while (i < this.items.length && now - this.items[i][0] > WINDOW_MS) ++i;
    if (i) this.items.splice(0, i);
  }
  summary(now) {
    this.trim(now);
    const v = this.items.map((x) => x[1]).sort((a, b) => a - b);
    if (!v.length) return { count: 0, median: NaN, p95: NaN, mean: NaN };
    const q = (f) => v[Math.min(v.length - 1, Math.floor(f * v.length))];
    return { count: v.length, median: q(0.5), p95: q(0.95), mean: v.reduce((a, b) => a + b) / v.length };
  }
}

const view = document.getElementById('view');
const scene = new RoomScene(view, { antialias: params.get('aa') !== '0' });
const latency = new Window();
const captureToServer = new Window();
const serverToRender = new Window();
const decodeMs = new Window();
const meshMs = new Window();
const frames = new Window();
let pending = new Map(); // "sender/target" -> hand update not rendered yet
let rendered = 0;
let frozen = false; // tests: hold the hands still for a screenshot
const net = { state: 'starting', detail: '', selfId: 0, participants: [], clockOffsetMs: 0,
  rttMs: NaN, senders: {} };

const el = (id) => document.getElementById(id);
document.getElementById('room').textContent = `room ${options.room}`;

function showState(state, detail) {
  const s = el('state');
  s.textContent = state;
  s.className = `state ${state}`;
  s.title = detail;
}

function placeSeatCamera() {
  if (seatView === null) return;
  for (const p of scene.participants.values()) {
    if (p.seat !== seatView) continue;
    scene.room.updateMatrixWorld();
    const toScene = new THREE.Matrix4().multiplyMatrices(scene.room.matrixWorld, p.group.matrix);
    // The user's eyes behind the desk (world y -0.55 m, 0.45 m above it), looking at the far
    // side of the workspace.
    const eye = new THREE.Vector3(0, -0.55, 0.45).applyMatrix4(toScene);
    const target = new THREE.Vector3(0, 0.3, 0).applyMatrix4(toScene);
    scene.camera.position.copy(eye);
    scene.controls.target.copy(target);
    scene.controls.update();
  }
}

// The network, the decoders and marching cubes live in a worker (worker.js).
const worker = new Worker(new URL('worker.js', import.meta.url), { type: 'module' });
worker.onmessage = (ev) => {
  const m = ev.data;
  if (m.type === 'state') {
    net.state = m.state;
    net.detail = m.detail;
    showState(m.state, m.detail);
  } else if (m.type === 'participants') {
    net.participants = m.list;
    net.selfId = m.selfId;
    scene.setParticipants(m.list);
    if (seatView === null) scene.frameSeats();
    else placeSeatCamera();
  } else if (m.type === 'clock') {
    net.clockOffsetMs = m.offsetMs;
    net.rttMs = m.rttMs;
  } else if (m.type === 'senders') {
    net.senders = m.stats;
  } else if (m.type === 'face') {
    // Decoded by the browser off the main thread; flipped for WebGL (ImageBitmap ignores flipY).
    createImageBitmap(new Blob([m.jpeg], { type: 'image/jpeg' }), { imageOrientation: 'flipY' })
      .then((bitmap) => { if (!scene.updateFace(m.sender, bitmap, m.stampMs)) bitmap.close(); })
      .catch(() => {});
  } else if (m.type === 'hands') {
    const now = nowMs();
    for (const h of m.hands) {
      decodeMs.push(now, h.decodeMs);
      meshMs.push(now, h.meshMs);
      pending.set(`${h.sender}/${h.target}`, h);
    }
  }
};
worker.onerror = (e) => showState('error', `worker: ${e.message}`);
worker.postMessage({ type: 'start', options });

function fmt(x, digits = 1) {
  return Number.isFinite(x) ? x.toFixed(digits) : '-';
}

function updateHud(now) {
  const fps = frames.summary(now).count / (WINDOW_MS / 1000);
  el('fps').textContent = `${fmt(fps)} fps`;
  const l = latency.summary(now);
  el('latency').textContent = l.count ? `${fmt(l.median)} / ${fmt(l.p95)} ms` : '-';
  el('decode').textContent = `${fmt(decodeMs.summary(now).mean, 2)} + ${fmt(meshMs.summary(now).mean, 2)} ms`;
  const items = net.participants.map((p) => {
    const s = net.senders[p.id];
    const colour = p.role === 'rig' ? scene.participantColour(p.id) : 'transparent';
    const you = p.id === net.selfId ? ' (this page)' : '';
    const detail = p.role === 'rig'
      ? ` seat ${p.seat}, ${scene.handCount(p.id)} hand(s)${s && s.errors ? `, ${s.errors} bad` : ''}`
      : ' viewer';
    return `<li><span class="swatch" style="background:${colour}"></span>${escapeHtml(p.name)}${you}:${detail}</li>`;
  });
  el('participants').innerHTML = items.join('');
}

function escapeHtml(s) {
  return String(s).replace(/[&<>"']/g, (c) => `&#${c.charCodeAt(0)};`);
}

let lastHud = 0;
function frame() {
  requestAnimationFrame(frame);
  const now = nowMs();
  const shownNow = [];
  if (!frozen) {
    for (const h of pending.values()) if (scene.updateHand(h.sender, h.target, h.mesh, now)) shownNow.push(h);
    pending.clear();
    scene.removeStaleHands(now, HAND_TIMEOUT_MS);
  }
  scene.render();
  ++rendered;
  frames.push(now, 1);
  // The frame is on screen once render() returned (the compositor adds at most one vsync).
  const shown = nowMs() + net.clockOffsetMs; // server clock
  for (const h of shownNow) {
    latency.push(now, shown - h.stampMs);
    captureToServer.push(now, h.serverMs - h.stampMs);
    serverToRender.push(now, shown - h.serverMs);
  }
  if (now - lastHud > 250) {
    lastHud = now;
    updateHud(now);
  }
}

// For tests and tools (the Chromium end-to-end test reads these).
window.cve = {
  stats() {
    const now = nowMs();
    return {
      state: net.state,
      detail: net.detail,
      self: net.selfId,
      clockOffsetMs: net.clockOffsetMs,
      rttMs: net.rttMs,
      renderFps: frames.summary(now).count / (WINDOW_MS / 1000),
      framesRendered: rendered,
      latencyMs: latency.summary(now),
      captureToServerMs: captureToServer.summary(now),
      serverToRenderMs: serverToRender.summary(now),
      decodeMs: decodeMs.summary(now),
      meshMs: meshMs.summary(now),
      participants: net.participants.map((p) => ({
        id: p.id, name: p.name, role: p.role, seat: p.seat, hands: scene.handCount(p.id),
        ...(net.senders[p.id] || {}), facesShown: scene.faceCount(p.id),
      })),
    };
  },
  handScreenBoxes: () => scene.handScreenBoxes(),
  faceScreenBoxes: () => scene.faceScreenBoxes(),
  // Holds (true) or releases the hands; resolves once a frame has been rendered in that state.
  freeze(on) {
    frozen = on;
    return new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
  },
};

requestAnimationFrame(frame);
