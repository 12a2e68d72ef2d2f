// The 3D view of the same scene (three.js): extruded obstacles (the all-altitude ones tall,
// dark red and see-through), flat targets, drones with drop lines to the ground and trails,
// an altitude ruler, and orbit controls. World x east, y north, z up maps to three's
// (x, z, -y).

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { shapeOutline } from "./world.js";

const ALL_ALTITUDE_DRAW_M = 150;

function shape2d(points) {
  const shape = new THREE.Shape();
  points.forEach(([x, y], k) => (k === 0 ? shape.moveTo(x, y) : shape.lineTo(x, y)));
  shape.closePath();
  return shape;
}

// A renderer without a GPU (SwiftShader, llvmpipe: remote desktops, virtual machines) draws
// every pixel on the CPU, where multisampling costs several times a plain frame: there the
// view renders without it, so a live swarm stays smooth and the machine stays usable.
function softwareRenderer() {
  const gl = document.createElement("canvas").getContext("webgl2");
  if (!gl) return false;
  const info = gl.getExtension("WEBGL_debug_renderer_info");
  const name = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  gl.getExtension("WEBGL_lose_context")?.loseContext();
  return /swiftshader|llvmpipe|softpipe|software/i.test(name);
}

function textSprite(text, heightM) {
  const canvas = document.createElement("canvas");
  canvas.width = 256; canvas.height = 64;
  const ctx = canvas.getContext("2d");
  ctx.fillStyle = "rgba(255,255,255,0.85)"; ctx.fillRect(0, 0, 256, 64);
  ctx.fillStyle = "#1b1b1b"; ctx.font = "bold 34px sans-serif"; ctx.textBaseline = "middle";
  ctx.fillText(text, 10, 32);
  const sprite = new THREE.Sprite(new THREE.SpriteMaterial({ map: new THREE.CanvasTexture(canvas), depthTest: false }));
  sprite.scale.set(heightM * 4, heightM, 1);
  return sprite;
}

export class View3D {
  constructor(container) {
    this.container = container;
    this.software = softwareRenderer();
    this.renderer = new THREE.WebGLRenderer({ antialias: !this.software, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    container.appendChild(this.renderer.domElement);
    this.canvas = this.renderer.domElement;
    this.scene = new THREE.Scene();
    this.scene.background = new THREE.Color("#dfe7ef");
    this.camera = new THREE.PerspectiveCamera(50, 1, 1, 20000);
    this.controls = new OrbitControls(this.camera, this.canvas);
    this.controls.addEventListener("change", () => this.render());
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x8899aa, 2.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.4);
    sun.position.set(300, 800, 200);
    this.scene.add(sun);
    this.static = new THREE.Group();
    this.dynamic = new THREE.Group();
    this.scene.add(this.static, this.dynamic);
    this.drones = new Map();
    this.selected = null;
    this._dirty = false;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
    const loop = () => { if (this._dirty) this.render(); requestAnimationFrame(loop); };
    requestAnimationFrame(loop);
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  setWorld(world) {
    this.static.clear();
    this.dynamic.clear();
    this.drones.clear();
    const [x0, y0, x1, y1] = world.bounds;
    const size = Math.max(x1 - x0, y1 - y0);
    this.droneSize = Math.max(1.5, size / 160);
    const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
    const ground = new THREE.Mesh(new THREE.PlaneGeometry(x1 - x0, y1 - y0),
      new THREE.MeshLambertMaterial({ color: "#f4f1ea" }));
    ground.rotation.x = -Math.PI / 2;
    ground.position.set(cx, 0, -cy);
    this.static.add(ground);
    const grid = new THREE.GridHelper(size, 20, 0xb8c2cc, 0xd3dae1);
    grid.position.set(cx, 0.05, -cy);
    this.static.add(grid);
    for (const t of world.targets) this.static.add(this._target(t));
    for (const o of world.obstacles) this.static.add(this._obstacle(o));
    this._ruler(x0, y0, size);
    this.camera.position.set(cx - size * 0.15, size * 0.65, -cy + size * 0.85);
    this.controls.target.set(cx, 0, -cy);
    this.controls.update();
    this.render();
  }

  _obstacle(o) {
    const height = o.allAltitudes ? ALL_ALTITUDE_DRAW_M : Math.max(0.5, o.height);
    const geometry = new THREE.ExtrudeGeometry(shape2d(shapeOutline(o.shape, 28)), { depth: height, bevelEnabled: false });
    geometry.rotateX(-Math.PI / 2);
    const material = o.allAltitudes
      ? new THREE.MeshLambertMaterial({ color: "#9b1d2a", transparent: true, opacity: 0.55 })
      : new THREE.MeshLambertMaterial({ color: "#8d99ae" });
    return new THREE.Mesh(geometry, material);
  }

  _target(t) {
    if (t.area) {
      const geometry = new THREE.ShapeGeometry(shape2d(shapeOutline(t.shape, 64)));
      geometry.rotateX(-Math.PI / 2);
      const mesh = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ color: "#2ecc71", transparent: true, opacity: 0.35, side: THREE.DoubleSide }));
      mesh.position.y = 0.2;
      return mesh;
    }
    const r = Math.max(this.droneSize, t.radius);
    const mesh = new THREE.Mesh(new THREE.CylinderGeometry(r, r, 1, 24),
      new THREE.MeshLambertMaterial({ color: t.station ? "#2e86de" : "#f39c12" }));
    mesh.position.set(t.shape.x, 0.5, -t.shape.y);
    return mesh;
  }

  _ruler(x0, y0, size) {
    const top = Math.max(60, Math.min(150, size / 8));
    const points = [new THREE.Vector3(x0, 0, -y0), new THREE.Vector3(x0, top, -y0)];
    this.static.add(new THREE.Line(new THREE.BufferGeometry().setFromPoints(points), new THREE.LineBasicMaterial({ color: "#1b1b1b" })));
    for (let h = 0; h <= top; h += top >= 100 ? 50 : 20) {
      const label = textSprite(`${h} m`, this.droneSize * 2.5);
      label.position.set(x0 + this.droneSize * 5, h, -y0);
      this.static.add(label);
    }
  }

  _drone(id) {
    const body = new THREE.Mesh(new THREE.SphereGeometry(this.droneSize, 16, 12), new THREE.MeshLambertMaterial({ color: "#e6007e" }));
    const nose = new THREE.Mesh(new THREE.ConeGeometry(this.droneSize * 0.6, this.droneSize * 2, 10), new THREE.MeshLambertMaterial({ color: "#1b1b1b" }));
    nose.rotation.x = -Math.PI / 2;
    nose.position.z = -this.droneSize * 1.6;
    const heading = new THREE.Group();
    heading.add(body, nose);
    const drop = new THREE.Line(new THREE.BufferGeometry().setFromPoints([new THREE.Vector3(), new THREE.Vector3()]),
      new THREE.LineBasicMaterial({ color: "#555555" }));
    drop.frustumCulled = false;
    const trail = new THREE.Line(new THREE.BufferGeometry(), new THREE.LineBasicMaterial({ color: "#e6007e" }));
    trail.frustumCulled = false;
    this.dynamic.add(heading, drop, trail);
    const entry = { heading, drop, trail, label: null, labelText: "", points: 0, first: null, capacity: 0 };
    this.drones.set(id, entry);
    return entry;
  }

  update(drones, trails, selected) {
    for (const d of drones) {
      const entry = this.drones.get(d.id) || this._drone(d.id);
      entry.heading.position.set(d.x, d.z, -d.y);
      entry.heading.rotation.y = -((d.yaw || 0) * Math.PI) / 180;
      const drop = entry.drop.geometry.attributes.position;
      drop.setXYZ(0, d.x, d.z, -d.y); drop.setXYZ(1, d.x, 0, -d.y); drop.needsUpdate = true;
      const trail = trails.get(d.id);
      if (trail && trail.length > 1) this._trail(entry, trail);
      const text = d.id === selected ? `${d.id} ${d.z.toFixed(1)} m` : "";
      if (text !== entry.labelText) {
        if (entry.label) this.dynamic.remove(entry.label);
        entry.label = text ? textSprite(text, this.droneSize * 6) : null;
        if (entry.label) this.dynamic.add(entry.label);
        entry.labelText = text;
      }
      if (entry.label) entry.label.position.set(d.x, d.z + this.droneSize * 7, -d.y);
    }
    this._dirty = true;
  }

  // Trails grow by appending to a buffer with room to spare; a trail that changed otherwise
  // (a replay scrubbed back, a trail restarted) is written again.
  _trail(entry, trail) {
    const n = trail.length;
    const appendable = entry.first === trail[0] && n >= entry.points && n <= entry.capacity;
    if (!appendable) {
      entry.capacity = Math.max(64, 2 ** Math.ceil(Math.log2(n + 1)));
      entry.trail.geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(entry.capacity * 3), 3));
      entry.points = 0;
      entry.first = trail[0];
    }
    const attr = entry.trail.geometry.attributes.position;
    for (let k = Math.max(0, entry.points - 1); k < n; k++) {
      const [x, y, , z] = trail[k];
      attr.setXYZ(k, x, z ?? 0, -y);
    }
    attr.needsUpdate = true;
    entry.points = n;
    entry.trail.geometry.setDrawRange(0, n);
  }

  render() {
    this._dirty = false;
    this.renderer.render(this.scene, this.camera);
  }
}
