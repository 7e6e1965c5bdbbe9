// The page's network and geometry thread: the room connection, the codec decoders and marching
// cubes run here, so a busy page (or a slow software renderer) never delays the decoding of
// hand messages, and rendering never waits for a mesh. Posts to the page:
//   {type:'state', state, detail}   {type:'participants', list, selfId}
//   {type:'clock', offsetMs, rttMs} {type:'hands', hands: [...]} (typed arrays transferred)
//   {type:'senders', stats}         (every 500 ms)
//   {type:'face', sender, jpeg, stampMs} (a participant's face picture; jpeg transferred)
import { isFaceMessage, parseFaceMessage } from './face_message.js';
import { HandStreams } from './hand_streams.js';
import { RoomConnection } from './room_connection.js';

const streams = new HandStreams();
let flushScheduled = false;

// Meshes what arrived since the last flush; runs once the queued messages are decoded.
function flush() {
  flushScheduled = false;
  const hands = streams.mesh();
  if (!hands.length) return;
  const transfer = [];
  for (const h of hands) {
    transfer.push(h.mesh.positions.buffer, h.mesh.indices.buffer);
    if (h.mesh.normals) transfer.push(h.mesh.normals.buffer);
  }
  postMessage({ type: 'hands', hands }, transfer);
}

self.onmessage = (ev) => {
  if (ev.data.type !== 'start') return;
  const connection = new RoomConnection({
    ...ev.data.options,
    onState: (state, detail) => postMessage({ type: 'state', state, detail }),
    onParticipants: (list, selfId) => {
      streams.forget(new Set(list.map((p) => p.id)));
      postMessage({ type: 'participants', list, selfId });
    },
    onClock: (offsetMs, rttMs) => postMessage({ type: 'clock', offsetMs, rttMs }),
    onHand: (relay) => {
      const s = streams.noteSequence(relay);
      if (isFaceMessage(relay.payload)) {
        const f = parseFaceMessage(relay.payload);
        if (!f.ok) {
          ++s.badFaces;
          return;
        }
        ++s.faces;
        const jpeg = f.jpeg.slice(); // its own buffer, to transfer
        postMessage({ type: 'face', sender: relay.sender, jpeg, stampMs: f.stampMs }, [jpeg.buffer]);
        return;
      }
      if (!streams.decode(relay) || flushScheduled) return;
      flushScheduled = true;
      setTimeout(flush, 0);
    },
  });
  connection.start();
  setInterval(() => postMessage({ type: 'senders', stats: streams.stats() }), 500);
};
