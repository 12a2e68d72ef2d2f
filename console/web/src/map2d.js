// The 2D top-down map: metres east (x) and north (y), north up, with a scale bar; obstacles,
// targets, drones with heading and fading trails; pan (drag) and zoom (wheel); clicks report
// the world point and the drone under the pointer. Drones closer on screen than a dot's width
// are drawn as a cluster (one count badge, which a click zooms into; one label naming them);
// labels are placed where they overprint nothing (around the dot, further out with a leader
// line, or left out). Point obstacles are crossed squares, never dots a drone could be taken
// for.

import { shapeOutline } from "./world.js";

export const COLORS = {
  background: "#eef1f4", grid: "#dde3e9", building: "#8d99ae", buildingEdge: "#5c677d",
  wall: "#2b2d42", wallEdge: "#d90429", area: "rgba(46, 204, 113, 0.18)", areaEdge: "#1e8449",
  point: "#f39c12", station: "#2e86de", drone: "#e6007e", selected: "#ffb400",
  trail: [230, 0, 126], perception: "rgba(46, 134, 222, 0.55)", task: "rgba(230, 0, 126, 0.5)",
};
export const DRONE_RADIUS_PX = 6;
const CLUSTER_PX = 2 * DRONE_RADIUS_PX + 2;  // drones closer than this on screen: one cluster
const POINT_OBSTACLE_PX = 10;  // an obstacle drawn smaller than this gets the point glyph
const MAX_LABELLED = 400;  // beyond this many drones only the selected ones are labelled
const STATUS_COLORS = { ok: "#1e8449", accepted: "#1f5fbf", partial: "#b9770e", blocked: "#b9770e", interrupted: "#b9770e" };
const TRAIL_FADE_S = 120;

export class Map2D {
  constructor(canvas, { onClick = null, onDragStart = null } = {}) {
    this.canvas = canvas;
    this.onDragStart = onDragStart;
    this.ctx = canvas.getContext("2d");
    this.onClick = onClick;
    this.world = null;
    this.drones = [];
    this.trails = new Map();
    this.now = 0;
    this.selected = null;
    this.chosen = new Set();  // drones picked for a command (live view)
    this.labelBoxes = [];  // where drone labels went in the last draw: {text, x, y, w, h}
    this._occupied = new Occupancy();
    this.toggles = { perception: false, task: false, labels: true };
    this.overlays = [];
    this.view = { scale: 1, cx: 0, cy: 0 };
    this.dpr = window.devicePixelRatio || 1;
    this._dirty = true;
    this._fitted = false;
    this._bindInput();
    new ResizeObserver(() => this._resize()).observe(canvas);
    this._resize();
    const loop = () => { if (this._dirty) this.draw(); requestAnimationFrame(loop); };
    requestAnimationFrame(loop);
  }

  get width() { return this.canvas.clientWidth; }
  get height() { return this.canvas.clientHeight; }

  _resize() {
    this.dpr = window.devicePixelRatio || 1;
    this.canvas.width = Math.max(1, Math.round(this.width * this.dpr));
    this.canvas.height = Math.max(1, Math.round(this.height * this.dpr));
    if (!this._fitted && this.world) this.fit();
    this.redraw();
  }

  redraw() { this._dirty = true; }

  setWorld(world) {
    this.world = world;
    this._fitted = false;
    if (this.width > 0) this.fit();
    this.redraw();
  }

  fit() {
    if (!this.world) return;
    const [x0, y0, x1, y1] = this.world.bounds;
    const scale = Math.min(this.width / Math.max(1, x1 - x0), this.height / Math.max(1, y1 - y0));
    this.view = { scale: scale > 0 ? scale : 1, cx: (x0 + x1) / 2, cy: (y0 + y1) / 2 };
    this._fitted = this.width > 0;
    this.redraw();
  }

  toScreen(x, y) {
    const v = this.view;
    return [this.width / 2 + (x - v.cx) * v.scale, this.height / 2 - (y - v.cy) * v.scale];
  }

  toWorld(px, py) {
    const v = this.view;
    return [v.cx + (px - this.width / 2) / v.scale, v.cy - (py - this.height / 2) / v.scale];
  }

  droneAt(px, py) {
    let best = null, bestD = 12;
    for (const d of this.drones) {
      const [sx, sy] = this.toScreen(d.x, d.y);
      const dist = Math.hypot(sx - px, sy - py);
      if (dist < bestD) { best = d.id; bestD = dist; }
    }
    return best;
  }

  badgeAt(px, py) {
    return (this._badges || []).find((b) => Math.hypot(b.x - px, b.y - py) <= 9) || null;
  }

  zoomAt(px, py, factor) {
    // Zoom by `factor` keeping the world point under screen point (px, py) where it is.
    const [wx, wy] = this.toWorld(px, py);
    this.view.scale = Math.min(200, Math.max(0.01, this.view.scale * factor));
    const [nx, ny] = this.toWorld(px, py);
    this.view.cx += wx - nx;
    this.view.cy += wy - ny;
    this.redraw();
  }

  _bindInput() {
    let drag = null;
    this.canvas.addEventListener("mousedown", (e) => {
      const handler = this.onDragStart ? this.onDragStart(this.toWorld(e.offsetX, e.offsetY), e) : null;
      drag = { x: e.offsetX, y: e.offsetY, cx: this.view.cx, cy: this.view.cy, moved: false, handler };
    });
    window.addEventListener("mousemove", (e) => {
      if (!drag) return;
      const rect = this.canvas.getBoundingClientRect();
      const dx = e.clientX - rect.left - drag.x, dy = e.clientY - rect.top - drag.y;
      if (Math.abs(dx) + Math.abs(dy) > 3) drag.moved = true;
      if (drag.moved && drag.handler) {
        drag.handler.move(this.toWorld(e.clientX - rect.left, e.clientY - rect.top));
        this.redraw();
      } else if (drag.moved) {
        this.view.cx = drag.cx - dx / this.view.scale;
        this.view.cy = drag.cy + dy / this.view.scale;
        this.redraw();
      }
    });
    window.addEventListener("mouseup", (e) => {
      if (drag && drag.moved && drag.handler) drag.handler.end();
      const badge = drag && !drag.moved && e.target === this.canvas ? this.badgeAt(e.offsetX, e.offsetY) : null;
      if (badge) {
        this.zoomAt(badge.x, badge.y, 4);  // a cluster's count badge: zoom in to split it
      } else if (drag && !drag.moved && this.onClick && e.target === this.canvas) {
        const [x, y] = this.toWorld(e.offsetX, e.offsetY);
        this.onClick({ x, y, drone: this.droneAt(e.offsetX, e.offsetY), event: e });
      }
      drag = null;
    });
    this.canvas.addEventListener("wheel", (e) => {
      e.preventDefault();
      this.zoomAt(e.offsetX, e.offsetY, Math.exp(-e.deltaY * 0.0015));
    }, { passive: false });
  }

  _path(points) {
    const ctx = this.ctx;
    ctx.beginPath();
    points.forEach(([x, y], k) => {
      const [sx, sy] = this.toScreen(x, y);
      if (k === 0) ctx.moveTo(sx, sy); else ctx.lineTo(sx, sy);
    });
    ctx.closePath();
  }

  _circle(x, y, radiusM) {
    const [sx, sy] = this.toScreen(x, y);
    this.ctx.beginPath();
    this.ctx.arc(sx, sy, Math.max(0.5, radiusM * this.view.scale), 0, 2 * Math.PI);
  }

  draw() {
    this._dirty = false;
    const ctx = this.ctx;
    ctx.setTransform(this.dpr, 0, 0, this.dpr, 0, 0);
    ctx.fillStyle = COLORS.background;
    ctx.fillRect(0, 0, this.width, this.height);
    this._occupied = new Occupancy();
    if (!this.world) return;
    this._grid();
    this._targets();
    this._obstacles();
    for (const overlay of this.overlays) overlay(ctx, this, "below");
    this._trails();
    this._drones();
    for (const overlay of this.overlays) overlay(ctx, this, "above");
    this._scaleBar();
  }

  _grid() {
    const ctx = this.ctx;
    const step = niceStep(80 / this.view.scale);
    const [x0, y1] = this.toWorld(0, 0), [x1, y0] = this.toWorld(this.width, this.height);
    ctx.strokeStyle = COLORS.grid;
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let x = Math.ceil(x0 / step) * step; x <= x1; x += step) {
      const [sx] = this.toScreen(x, 0); ctx.moveTo(sx, 0); ctx.lineTo(sx, this.height);
    }
    for (let y = Math.ceil(y0 / step) * step; y <= y1; y += step) {
      const [, sy] = this.toScreen(0, y); ctx.moveTo(0, sy); ctx.lineTo(this.width, sy);
    }
    ctx.stroke();
  }

  _targets() {
    const ctx = this.ctx;
    for (const t of this.world.targets) {
      if (t.area) {
        this._path(shapeOutline(t.shape, 64));
        ctx.fillStyle = COLORS.area; ctx.fill();
        ctx.strokeStyle = COLORS.areaEdge; ctx.lineWidth = 1.5; ctx.stroke();
      } else {
        const [sx, sy] = this.toScreen(t.shape.x, t.shape.y);
        const r = Math.max(4, t.radius * this.view.scale);
        ctx.beginPath();
        if (t.station) ctx.rect(sx - r, sy - r, 2 * r, 2 * r);
        else { ctx.moveTo(sx, sy - r); ctx.lineTo(sx + r, sy); ctx.lineTo(sx, sy + r); ctx.lineTo(sx - r, sy); ctx.closePath(); }
        ctx.fillStyle = t.station ? COLORS.station : COLORS.point; ctx.fill();
      }
      if (this.toggles.labels) this._label(t.name, t.shape.type === "polygon" ? centroid(t.shape.points) : [t.shape.x, t.shape.y], "#145a32", 12);
    }
  }

  _obstacles() {
    const ctx = this.ctx;
    for (const o of this.world.obstacles) {
      const s = o.shape;
      const small = s.type !== "polygon" && 2 * Math.max(s.rx, s.ry) * this.view.scale < POINT_OBSTACLE_PX;
      if (o.kind === "point" || small) {
        this._pointObstacle(o);
        continue;
      }
      this._path(shapeOutline(s, 48));
      ctx.fillStyle = o.allAltitudes ? COLORS.wall : COLORS.building;
      ctx.fill();
      ctx.strokeStyle = o.allAltitudes ? COLORS.wallEdge : COLORS.buildingEdge;
      ctx.lineWidth = o.allAltitudes ? 2 : 1;
      ctx.stroke();
      const text = o.allAltitudes ? "all alt." : `${o.height.toFixed(0)} m`;
      if (this.toggles.labels && this._fits(text, s)) {
        const c = s.type === "polygon" ? centroid(s.points) : [s.x, s.y];
        this._label(text, c, "#ffffff", 0, true);
      }
    }
  }

  _fits(text, shape) {
    // An obstacle's label is drawn only inside its footprint, never spilling over its edge.
    const outline = shapeOutline(shape, 16).map(([x, y]) => this.toScreen(x, y));
    const xs = outline.map((p) => p[0]), ys = outline.map((p) => p[1]);
    this.ctx.font = "11px sans-serif";
    const w = this.ctx.measureText(text).width;
    return Math.max(...xs) - Math.min(...xs) > w + 6 && Math.max(...ys) - Math.min(...ys) > 16;
  }

  _pointObstacle(o) {
    // A crossed square (its footprint, at least POINT_OBSTACLE_PX wide): never a filled dot.
    const ctx = this.ctx;
    const [sx, sy] = this.toScreen(o.shape.x, o.shape.y);
    const half = Math.max(POINT_OBSTACLE_PX / 2, Math.max(o.shape.rx, o.shape.ry) * this.view.scale);
    ctx.fillStyle = "#ffffff";
    ctx.fillRect(sx - half, sy - half, 2 * half, 2 * half);
    ctx.strokeStyle = o.allAltitudes ? COLORS.wallEdge : COLORS.buildingEdge;
    ctx.lineWidth = 2;
    ctx.strokeRect(sx - half, sy - half, 2 * half, 2 * half);
    ctx.beginPath();
    ctx.moveTo(sx - half, sy - half); ctx.lineTo(sx + half, sy + half);
    ctx.moveTo(sx + half, sy - half); ctx.lineTo(sx - half, sy + half);
    ctx.strokeStyle = COLORS.wall; ctx.lineWidth = 1.5; ctx.stroke();
    this._occupied.add({ x: sx - half, y: sy - half, w: 2 * half, h: 2 * half });
  }

  _label(text, [x, y], color, dy = 0, center = false) {
    const ctx = this.ctx;
    const [sx, sy] = this.toScreen(x, y);
    ctx.font = "11px sans-serif";
    ctx.textAlign = "center";
    ctx.textBaseline = center ? "middle" : "bottom";
    ctx.fillStyle = color;
    ctx.fillText(text, sx, sy - dy);
    const w = ctx.measureText(text).width;
    this._occupied.add({ x: sx - w / 2, y: center ? sy - 6 : sy - dy - 12, w, h: 12 });
  }

  _trails() {
    // Segments grouped into a few alpha steps by age: one stroke per step, not per segment.
    const ctx = this.ctx;
    const [r, g, b] = COLORS.trail;
    const steps = 6;
    const paths = Array.from({ length: steps }, () => new Path2D());
    const used = new Array(steps).fill(false);
    for (const trail of this.trails.values()) {
      for (let k = 1; k < trail.length; k++) {
        const age = this.now - trail[k][2];
        const step = Math.min(steps - 1, Math.max(0, Math.floor((age / TRAIL_FADE_S) * steps)));
        const [ax, ay] = this.toScreen(trail[k - 1][0], trail[k - 1][1]);
        const [bx, by] = this.toScreen(trail[k][0], trail[k][1]);
        paths[step].moveTo(ax, ay);
        paths[step].lineTo(bx, by);
        used[step] = true;
      }
    }
    ctx.lineWidth = 2;
    for (let step = steps - 1; step >= 0; step--) {
      if (!used[step]) continue;
      const alpha = Math.max(0.08, 0.8 * (1 - step / steps));
      ctx.strokeStyle = `rgba(${r}, ${g}, ${b}, ${alpha.toFixed(3)})`;
      ctx.stroke(paths[step]);
    }
  }

  _drones() {
    const ctx = this.ctx;
    const spec = new Map((this.world.drones || []).map((d) => [d.id, d]));
    for (const d of this.drones) {
      const s = spec.get(d.id);
      if (s && this.toggles.perception) {
        this._circle(d.x, d.y, s.perceived);
        ctx.setLineDash([5, 4]); ctx.strokeStyle = COLORS.perception; ctx.lineWidth = 1; ctx.stroke(); ctx.setLineDash([]);
      }
      if (s && this.toggles.task) {
        this._circle(d.x, d.y, s.taskRadius);
        ctx.strokeStyle = COLORS.task; ctx.lineWidth = 1; ctx.stroke();
      }
    }
    const placed = this.drones.map((d) => ({ d, at: this.toScreen(d.x, d.y) }));
    for (const { d, at: [sx, sy] } of placed) {
      const yaw = ((d.yaw || 0) * Math.PI) / 180;
      const hx = sx + Math.sin(yaw) * (DRONE_RADIUS_PX + 7), hy = sy - Math.cos(yaw) * (DRONE_RADIUS_PX + 7);
      ctx.strokeStyle = "#1b1b1b"; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.moveTo(sx, sy); ctx.lineTo(hx, hy); ctx.stroke();
      if (d.id === this.selected || this.chosen.has(d.id)) {
        ctx.beginPath(); ctx.arc(sx, sy, DRONE_RADIUS_PX + 4, 0, 2 * Math.PI);
        ctx.strokeStyle = COLORS.selected; ctx.lineWidth = d.id === this.selected ? 3 : 2; ctx.stroke();
      }
      ctx.beginPath(); ctx.arc(sx, sy, DRONE_RADIUS_PX, 0, 2 * Math.PI);
      ctx.fillStyle = COLORS.drone; ctx.fill();
      this._occupied.add({ x: sx - DRONE_RADIUS_PX, y: sy - DRONE_RADIUS_PX, w: 2 * DRONE_RADIUS_PX, h: 2 * DRONE_RADIUS_PX });
    }
    const clusters = clusterOf(placed, CLUSTER_PX);
    this._badges = [];
    for (const c of clusters) if (c.members.length > 1) this._badge(c);
    this.clusters = clusters.map((c) => ({ ids: c.members.map((m) => m.d.id), x: c.x, y: c.y }));
    this.labelBoxes = [];
    if (!this.toggles.labels) return;
    const rank = (c) => (c.members.some((m) => m.d.id === this.selected) ? 0 : c.members.some((m) => this.chosen.has(m.d.id)) ? 1 : 2);
    const ordered = [...clusters].sort((a, b) => rank(a) - rank(b));
    for (const c of ordered) {
      if (this.drones.length > MAX_LABELLED && rank(c) === 2) continue;
      this._droneLabel(c, rank(c) === 0);
    }
  }

  _badge(c) {
    const ctx = this.ctx;
    const bx = c.right + DRONE_RADIUS_PX + 2, by = c.top - DRONE_RADIUS_PX - 2;
    ctx.beginPath(); ctx.arc(bx, by, 7, 0, 2 * Math.PI);
    ctx.fillStyle = "#ffffff"; ctx.fill();
    ctx.strokeStyle = "#1b1b1b"; ctx.lineWidth = 1.5; ctx.stroke();
    ctx.font = "bold 10px sans-serif"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
    ctx.fillStyle = "#1b1b1b"; ctx.fillText(String(c.members.length), bx, by + 0.5);
    this._badges.push({ x: bx, y: by, ids: c.members.map((m) => m.d.id) });
    this._occupied.add({ x: bx - 7, y: by - 7, w: 14, h: 14 });
  }

  _droneLabel(c, force) {
    // The cluster's label (one drone: its id and the status of its last command) where it
    // overlaps nothing drawn so far: next to the dot, further out with a leader line, or not
    // at all (the selected drone's label always shows).
    const ctx = this.ctx;
    const ids = c.members.map((m) => m.d.id);
    const title = ids.length === 1 ? ids[0] : ids.length <= 3 ? ids.join(", ") : `${ids.slice(0, 2).join(", ")} +${ids.length - 2}`;
    const outcome = ids.length === 1 ? c.members[0].d.outcome : null;
    ctx.font = "bold 11px sans-serif";
    const titleW = ctx.measureText(title).width;
    ctx.font = "10px sans-serif";
    const lineW = outcome ? ctx.measureText(outcome.text).width : 0;
    const w = Math.max(titleW, lineW) + 4, h = outcome ? 26 : 14;
    const r = DRONE_RADIUS_PX + 3;
    let box = null, leader = false;
    for (const [ring, far] of [[r, false], [r + 22, true], [r + 46, true]]) {
      for (const [ux, uy] of LABEL_SPOTS) {
        const x = c.x + ux * ring + (ux < 0 ? -w : ux === 0 ? -w / 2 : 0);
        const y = c.y + uy * ring + (uy < 0 ? -h : uy === 0 ? -h / 2 : 0);
        const spot = { x, y, w, h };
        if (x < 0 || y < 0 || x + w > this.width || y + h > this.height) continue;
        if (this._occupied.hits(spot)) continue;
        box = spot; leader = far; break;
      }
      if (box) break;
    }
    if (!box && !force) return;
    if (!box) { box = { x: c.x + r, y: c.y - h / 2, w, h }; }
    if (leader) {
      ctx.strokeStyle = "rgba(27, 27, 27, 0.6)"; ctx.lineWidth = 1;
      ctx.beginPath(); ctx.moveTo(c.x, c.y);
      ctx.lineTo(Math.min(Math.max(c.x, box.x), box.x + box.w), Math.min(Math.max(c.y, box.y), box.y + box.h)); ctx.stroke();
    }
    ctx.fillStyle = "rgba(255, 255, 255, 0.8)";
    ctx.fillRect(box.x, box.y, box.w, box.h);
    ctx.textAlign = "left"; ctx.textBaseline = "top";
    ctx.font = "bold 11px sans-serif"; ctx.fillStyle = "#1b1b1b";
    ctx.fillText(title, box.x + 2, box.y + 1);
    if (outcome) {
      ctx.font = "10px sans-serif"; ctx.fillStyle = STATUS_COLORS[outcome.status] || "#c0392b";
      ctx.fillText(outcome.text, box.x + 2, box.y + 14);
    }
    this._occupied.add(box);
    this.labelBoxes.push({ text: title, ids, ...box });
  }

  _scaleBar() {
    const ctx = this.ctx;
    const metres = niceStep(120 / this.view.scale);
    const px = metres * this.view.scale;
    const x = 16, y = this.height - 18;
    ctx.fillStyle = "rgba(255,255,255,0.85)";
    ctx.fillRect(x - 6, y - 18, px + 12, 28);
    ctx.strokeStyle = "#1b1b1b"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.moveTo(x, y - 5); ctx.lineTo(x, y); ctx.lineTo(x + px, y); ctx.lineTo(x + px, y - 5); ctx.stroke();
    ctx.font = "11px sans-serif"; ctx.fillStyle = "#1b1b1b"; ctx.textAlign = "center"; ctx.textBaseline = "bottom";
    ctx.fillText(metres >= 1000 ? `${metres / 1000} km` : `${metres} m`, x + px / 2, y - 4);
  }
}

// Where a label may go around a dot, in order of preference (unit offsets, y down).
const LABEL_SPOTS = [[1, 0], [-1, 0], [0, 1], [0, -1], [1, 1], [-1, 1], [1, -1], [-1, -1]];

function overlaps(a, b) {
  return a.x < b.x + b.w && b.x < a.x + a.w && a.y < b.y + b.h && b.y < a.y + a.h;
}

// Screen boxes already drawn on, bucketed in a grid: a label's candidate spot is checked
// against the boxes of the cells it covers only.
class Occupancy {
  constructor(cellPx = 48) { this.cell = cellPx; this.cells = new Map(); }

  _keys(box, visit) {
    const c = this.cell;
    for (let i = Math.floor(box.x / c); i <= Math.floor((box.x + box.w) / c); i++) {
      for (let j = Math.floor(box.y / c); j <= Math.floor((box.y + box.h) / c); j++) visit(`${i},${j}`);
    }
  }

  add(box) {
    this._keys(box, (key) => { if (!this.cells.has(key)) this.cells.set(key, []); this.cells.get(key).push(box); });
  }

  hits(box) {
    let hit = false;
    this._keys(box, (key) => { if (!hit) hit = (this.cells.get(key) || []).some((o) => overlaps(o, box)); });
    return hit;
  }
}

// Drones linked by gaps under `px` on screen (single link: a chain of close drones is one
// cluster), each cluster at the centre of its members, in scene order of their first member.
export function clusterOf(placed, px) {
  const parent = placed.map((_, k) => k);
  const find = (k) => { while (parent[k] !== k) { parent[k] = parent[parent[k]]; k = parent[k]; } return k; };
  const cells = new Map();
  placed.forEach((item, k) => {
    const gx = Math.floor(item.at[0] / px), gy = Math.floor(item.at[1] / px);
    for (let i = -1; i <= 1; i++) {
      for (let j = -1; j <= 1; j++) {
        for (const other of cells.get(`${gx + i},${gy + j}`) || []) {
          const [ox, oy] = placed[other].at;
          if (Math.hypot(ox - item.at[0], oy - item.at[1]) < px) {
            const a = find(k), b = find(other);
            if (a !== b) parent[Math.max(a, b)] = Math.min(a, b);
          }
        }
      }
    }
    const key = `${gx},${gy}`;
    if (!cells.has(key)) cells.set(key, []);
    cells.get(key).push(k);
  });
  const byRoot = new Map();
  placed.forEach((item, k) => {
    const root = find(k);
    if (!byRoot.has(root)) byRoot.set(root, { members: [] });
    byRoot.get(root).members.push(item);
  });
  return [...byRoot.values()].map((c) => {
    const xs = c.members.map((m) => m.at[0]), ys = c.members.map((m) => m.at[1]);
    return { ...c, x: xs.reduce((a, v) => a + v, 0) / xs.length, y: ys.reduce((a, v) => a + v, 0) / ys.length,
             right: Math.max(...xs), top: Math.min(...ys) };
  });
}

export function niceStep(raw) {
  const p = Math.pow(10, Math.floor(Math.log10(Math.max(raw, 1e-6))));
  for (const m of [1, 2, 5, 10]) if (m * p >= raw) return m * p;
  return 10 * p;
}

export function centroid(points) {
  let x = 0, y = 0;
  for (const [px, py] of points) { x += px; y += py; }
  return [x / Math.max(1, points.length), y / Math.max(1, points.length)];
}
