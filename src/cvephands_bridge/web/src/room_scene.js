// The virtual meeting room (thesis 7.5): a round table, one seat per participant and each
// participant's hands as skin-coloured meshes. Geometry follows the room frame of
// room_protocol.h: origin at the table centre on the table top, z up; a participant's hand
// meshes arrive in its rig's `world` frame and are placed with its seat_pose (room_T_world).
import * as THREE from 'three';
import { OrbitControls } from 'three/examples/jsm/controls/OrbitControls.js';

const TABLE_RADIUS = 1.15; // m: the seats' workspaces (0.9 m from the centre) lie on the table
const TABLE_HEIGHT = 0.75; // m above the floor, as a desk
// One skin tone per seat, so two participants' hands are told apart at a glance.
export const SKIN_TONES = ['#e0ac8c', '#c68863', '#f1c27d', '#a86b4c', '#e8b796', '#b5774f'];

function labelSprite(text, colour) {
  const canvas = document.createElement('canvas');
  canvas.width = 256;
  canvas.height = 64;
  const g = canvas.getContext('2d');
  g.fillStyle = 'rgba(20,26,36,0.75)';
  g.fillRect(0, 0, 256, 64);
  g.fillStyle = colour;
  g.fillRect(0, 0, 12, 64);
  g.fillStyle = '#e8ecf2';
  g.font = '28px system-ui, sans-serif';
  g.textBaseline = 'middle';
  g.fillText(text.slice(0, 16), 24, 32);
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({
    map: new THREE.CanvasTexture(canvas), depthWrite: false,
  }));
  sprite.scale.set(0.4, 0.1, 1);
  return sprite;
}

export class RoomScene {
  // antialias: off saves most of the frame time of a software renderer (SwiftShader).
  constructor(container, { antialias = true } = {}) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setSize(container.clientWidth, container.clientHeight);
    container.appendChild(this.renderer.domElement);

    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color('#1d2430');
    this.camera = new THREE.PerspectiveCamera(45, container.clientWidth / container.clientHeight,
      0.05, 50);
    this.camera.position.set(0, 1.7, 1.75);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.target.set(0, 0, 0);
    this.controls.update();
    // Until the user moves the view, frameSeats() keeps the occupied seats in view.
    this.userMoved = false;
    this.controls.addEventListener('start', () => { this.userMoved = true; });

    this.scene.add(new THREE.HemisphereLight('#f4f1ea', '#3a4150', 1.6));
    const sun = new THREE.DirectionalLight('#ffffff', 1.8);
    sun.position.set(1.5, 3, 1);
    this.scene.add(sun);

    // Room frame (z up) inside three.js' y-up world.
    this.room = new THREE.Group();
    this.room.rotation.x = -Math.PI / 2;
    this.scene.add(this.room);
    this.addFurniture();

    this.participants = new Map(); // id -> { group, label, chair, seat, name, hands: Map }
    window.addEventListener('resize', () => this.resize());
  }

  addFurniture() {
    const top = new THREE.Mesh(new THREE.CylinderGeometry(TABLE_RADIUS, TABLE_RADIUS, 0.04, 64),
      new THREE.MeshStandardMaterial({ color: '#5d6f86', roughness: 0.8 }));
    top.rotation.x = Math.PI / 2; // cylinder axis y -> room z
    top.position.z = -0.02;
    this.room.add(top);
    const legHeight = TABLE_HEIGHT - 0.04; // ends under the top (no z-fighting with it)
    const leg = new THREE.Mesh(new THREE.CylinderGeometry(0.08, 0.12, legHeight, 24),
      new THREE.MeshStandardMaterial({ color: '#3c4656' }));
    leg.rotation.x = Math.PI / 2;
    leg.position.z = -0.04 - legHeight / 2;
    this.room.add(leg);
    const floor = new THREE.Mesh(new THREE.CircleGeometry(4, 64),
      new THREE.MeshStandardMaterial({ color: '#27303d' }));
    floor.position.z = -TABLE_HEIGHT;
    this.room.add(floor);
  }

  resize() {
    const w = this.container.clientWidth;
    const h = this.container.clientHeight;
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.renderer.setSize(w, h);
  }

  // Seats for the rigs of the room; viewers (like this page) have none.
  setParticipants(list) {
    const rigs = new Map(list.filter((p) => p.role === 'rig' && p.seat_pose).map((p) => [p.id, p]));
    for (const [id, p] of this.participants) {
      if (!rigs.has(id)) {
        this.room.remove(p.group);
        p.group.traverse((o) => {
          if (o.geometry) o.geometry.dispose();
          if (o.material) {
            const map = o.material.map;
            if (map && map.image && map.image.close) map.image.close();
            if (map) map.dispose();
            o.material.dispose();
          }
        });
        p.material.dispose(); // the hands' (shared) material, also when no hand is left
        this.participants.delete(id);
      }
    }
    for (const [id, info] of rigs) {
      if (this.participants.has(id)) continue;
      const colour = SKIN_TONES[info.seat % SKIN_TONES.length];
      const group = new THREE.Group();
      group.matrixAutoUpdate = false;
      group.matrix.fromArray(info.seat_pose); // room_T_world, column-major
      this.room.add(group);
      // The user's chair behind the desk (world -y is away from the screen) and a name tag.
      const chair = new THREE.Mesh(new THREE.BoxGeometry(0.45, 0.45, 0.08),
        new THREE.MeshStandardMaterial({ color: '#44516a' }));
      chair.position.set(0, -0.75, -0.3);
      group.add(chair);
      const label = labelSprite(info.name || `participant ${id}`, colour);
      label.position.set(0, -0.55, 0.68);
      group.add(label);
      // The face video plane where the user's head is (world y -0.55, 0.45 m above the desk),
      // facing the table centre (world +y), upright (world +z); hidden until a picture arrives.
      const face = new THREE.Mesh(new THREE.PlaneGeometry(0.3, 0.3),
        new THREE.MeshBasicMaterial({ color: '#ffffff', side: THREE.DoubleSide }));
      face.quaternion.setFromRotationMatrix(new THREE.Matrix4().makeBasis(
        new THREE.Vector3(-1, 0, 0), new THREE.Vector3(0, 0, 1), new THREE.Vector3(0, 1, 0)));
      face.position.set(0, -0.55, 0.45);
      face.visible = false;
      group.add(face);
      const material = new THREE.MeshStandardMaterial({ color: colour, roughness: 0.55 });
      this.participants.set(id, { group, seat: info.seat, name: info.name, colour, material,
        hands: new Map(), face, faces: 0, faceStamp: -Infinity });
    }
  }

  // Looks across the table at the occupied seats, as a participant sitting opposite them.
  frameSeats() {
    if (this.userMoved || !this.participants.size) return;
    const d = new THREE.Vector3();
    for (const p of this.participants.values()) {
      d.x += p.group.matrix.elements[12];
      d.y += p.group.matrix.elements[13];
    }
    if (d.length() < 1e-6) d.set(1, 0, 0); // seats all around: any side will do
    d.normalize();
    this.room.updateMatrixWorld();
    // The seats' world origins are 0.9 m out, the hands work a little nearer their users and
    // the faces are 0.45 m above the table behind them: aim between, from above the near side.
    const target = new THREE.Vector3(1.1 * d.x, 1.1 * d.y, 0.2).applyMatrix4(this.room.matrixWorld);
    const eye = new THREE.Vector3(-0.5 * d.x, -0.5 * d.y, 1.25).applyMatrix4(this.room.matrixWorld);
    this.camera.position.copy(eye);
    this.controls.target.copy(target);
    this.controls.update();
  }

  // Shows a face picture (ImageBitmap, already flipped for WebGL) on the participant's plane,
  // unless a newer one is already there (pictures decode concurrently). One texture per
  // participant; the previous bitmap is released. False: the caller keeps (closes) the bitmap.
  updateFace(id, bitmap, stampMs) {
    const p = this.participants.get(id);
    if (!p || stampMs < p.faceStamp) return false;
    p.faceStamp = stampMs;
    const m = p.face.material;
    if (m.map) {
      if (m.map.image && m.map.image.close) m.map.image.close();
      m.map.image = bitmap;
    } else {
      m.map = new THREE.Texture(bitmap);
      m.map.flipY = false;
      m.map.colorSpace = THREE.SRGBColorSpace;
      m.needsUpdate = true;
    }
    m.map.needsUpdate = true;
    p.face.visible = true;
    ++p.faces;
    return true;
  }

  faceCount(id) {
    const p = this.participants.get(id);
    return p ? p.faces : 0;
  }

  participantColour(id) {
    const p = this.participants.get(id);
    return p ? p.colour : '#888';
  }

  // Replaces the mesh of hand `targetId` of participant `id` (mesh in the rig's world frame).
  updateHand(id, targetId, mesh, nowMs) {
    const p = this.participants.get(id);
    if (!p) return false;
    let hand = p.hands.get(targetId);
    if (!hand) {
      hand = { mesh: new THREE.Mesh(new THREE.BufferGeometry(), p.material), updated: 0 };
      p.group.add(hand.mesh);
      p.hands.set(targetId, hand);
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(mesh.positions, 3));
    if (mesh.normals) geometry.setAttribute('normal', new THREE.BufferAttribute(mesh.normals, 3));
    geometry.setIndex(new THREE.BufferAttribute(mesh.indices, 1));
    geometry.computeBoundingSphere();
    hand.mesh.geometry.dispose();
    hand.mesh.geometry = geometry;
    hand.updated = nowMs;
    return true;
  }

  // Hands not updated for maxAgeMs are gone (tracking lost, or the rig stopped).
  removeStaleHands(nowMs, maxAgeMs) {
    for (const p of this.participants.values()) {
      for (const [targetId, hand] of p.hands) {
        if (nowMs - hand.updated <= maxAgeMs) continue;
        p.group.remove(hand.mesh);
        hand.mesh.geometry.dispose();
        p.hands.delete(targetId);
      }
    }
  }

  handCount(id) {
    const p = this.participants.get(id);
    return p ? p.hands.size : 0;
  }

  render() {
    this.controls.update();
    this.renderer.render(this.scene, this.camera);
  }

  // Screen rectangles (CSS pixels, origin top left) of the visible face planes.
  faceScreenBoxes() {
    const boxes = [];
    this.scene.updateMatrixWorld();
    for (const [id, p] of this.participants) {
      if (!p.face.visible) continue;
      p.face.geometry.computeBoundingBox();
      boxes.push({ participant: id, ...this.screenBox(p.face.geometry.boundingBox, p.face.matrixWorld) });
    }
    return boxes;
  }

  // The screen rectangle of a box (local coordinates) under a world matrix.
  screenBox(b, matrixWorld) {
    const w = this.container.clientWidth;
    const h = this.container.clientHeight;
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    const v = new THREE.Vector3();
    for (let k = 0; k < 8; ++k) {
      v.set(k & 1 ? b.max.x : b.min.x, k & 2 ? b.max.y : b.min.y, k & 4 ? b.max.z : b.min.z);
      v.applyMatrix4(matrixWorld).project(this.camera);
      const sx = (v.x + 1) / 2 * w;
      const sy = (1 - v.y) / 2 * h;
      x0 = Math.min(x0, sx); x1 = Math.max(x1, sx);
      y0 = Math.min(y0, sy); y1 = Math.max(y1, sy);
    }
    return { x0, y0, x1, y1 };
  }

  // Screen rectangles (CSS pixels, origin top left) of every hand mesh on the page: where a
  // screenshot must show skin.
  handScreenBoxes() {
    const boxes = [];
    this.scene.updateMatrixWorld();
    for (const [id, p] of this.participants) {
      for (const [targetId, hand] of p.hands) {
        const g = hand.mesh.geometry;
        if (!g.attributes.position || g.attributes.position.count === 0) continue;
        g.computeBoundingBox();
        const { x0, y0, x1, y1 } = this.screenBox(g.boundingBox, hand.mesh.matrixWorld);
        boxes.push({ participant: id, seat: p.seat, target: targetId, colour: p.colour,
          vertices: g.attributes.position.count, x0, y0, x1, y1 });
      }
    }
    return boxes;
  }
}
