// The replay player: paths decoded from the stored replay (delta-encoded integers), the map and
// 3D view at any simulated time, and a timeline (play, pause, 1x-100x, scrub) carrying every
// event and, per drone, the agent's tool calls.

import { Map2D } from "./map2d.js";
import { argsText, el, legend, toggleBar } from "./panel.js";
import { View3D } from "./view3d.js";

const SCALE = [10, 10, 10, 10, 1, 10];
const COLUMNS = ["t", "x", "y", "z", "yaw", "bat"];
const SPEEDS = [1, 2, 5, 10, 20, 50, 100];
export const EVENT_COLORS = {
  photo: "#2e86de", obstacle_stop: "#d90429", failsafe: "#ff7f00", message_sent: "#8e44ad",
  message_broadcast: "#8e44ad", messages_read: "#b39ddb", message_dropped: "#8e44ad",
  operator_place: "#555555", operator_battery: "#555555", takeoff: "#27ae60", landed: "#16a085",
};
export const STATUS_COLORS = { ok: "#27ae60", partial: "#f39c12", blocked: "#e67e22", rejected: "#c0392b",
  timeout: "#c0392b", error: "#c0392b" };

export function decodePaths(paths, t0) {
  const out = new Map();
  for (const [id, columns] of Object.entries(paths || {})) {
    const n = columns.t.length;
    const cols = COLUMNS.map((name, c) => {
      const values = new Float64Array(n);
      let acc = 0;
      for (let k = 0; k < n; k++) { acc += columns[name][k]; values[k] = acc / SCALE[c]; }
      return values;
    });
    for (let k = 0; k < n; k++) cols[0][k] += t0;
    out.set(id, { t: cols[0], x: cols[1], y: cols[2], z: cols[3], yaw: cols[4], bat: cols[5] });
  }
  return out;
}

function lerpAngle(a, b, f) {
  const d = ((b - a + 540) % 360) - 180;
  return (a + d * f + 360) % 360;
}

export function sampleAt(path, t) {
  const ts = path.t;
  let lo = 0, hi = ts.length - 1;
  if (t <= ts[0]) hi = 0;
  else if (t >= ts[hi]) lo = hi;
  else {
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
  }
  const f = hi === lo ? 0 : (t - ts[lo]) / (ts[hi] - ts[lo]);
  const at = (a) => a[lo] + (a[hi] - a[lo]) * f;
  return { x: at(path.x), y: at(path.y), z: at(path.z), bat: at(path.bat), yaw: lerpAngle(path.yaw[lo], path.yaw[hi], f), index: lo };
}

export class ReplayPlayer {
  constructor(root, { world, replay, overlays = [] }) {
    this.world = world;
    this.replay = replay;
    this.t0 = replay.t0_s;
    this.t1 = Math.max(replay.t1_s, replay.t0_s + 0.1);
    this.paths = decodePaths(replay.paths, this.t0);
    this.t = this.t0;
    this.speed = 10;
    this.playing = false;
    this.events = (replay.events || []).map(([t, vehicle, kind, data]) => ({ t, vehicle, kind, data }));
    this.calls = replay.calls || [];
    const canvas = el("canvas", { id: "map2d" });
    const box3d = el("div", { id: "view3d" });
    this.timeLabel = el("span", { id: "replay-time" });
    this.slider = el("input", { id: "replay-slider", type: "range", min: 0, max: 1000, value: 0,
      oninput: (e) => this.seek(this.t0 + (this.t1 - this.t0) * Number(e.target.value) / 1000) });
    this.playButton = el("button", { id: "replay-play", onclick: () => this.toggle() }, "▶ play");
    const speed = el("select", { id: "replay-speed", onchange: (e) => { this.speed = Number(e.target.value); } },
      SPEEDS.map((s) => el("option", { value: s, ...(s === this.speed ? { selected: "" } : {}) }, `${s}x`)));
    this.lanes = el("canvas", { id: "timeline", onclick: (e) => this._laneClick(e) });
    this.tip = el("div", { id: "timeline-tip", class: "muted" }, "click the timeline to jump; events above, each drone's tool calls below");
    this.lanes.addEventListener("mousemove", (e) => this._laneHover(e));
    root.append(
      el("section", { class: "views" }, el("div", { class: "pane" }, canvas), el("div", { class: "pane" }, box3d)),
      el("div", { class: "timeline" }, this.playButton, speed, this.slider, this.timeLabel),
      this.lanes, this.tip);
    this.map = new Map2D(canvas, { onClick: (hit) => { if (hit.drone) { this.map.selected = hit.drone; this.render(); } } });
    this.map.overlays.push(...overlays);
    root.querySelector(".views").before(el("div", { class: "row" }, toggleBar(this.map), legend()));
    this.map.setWorld(world);
    this.view3d = null;
    // The map and timeline open first; the 3D scene (slower: WebGL, extruded obstacles) follows.
    this.ready3d = new Promise((resolve) => setTimeout(() => {
      this.view3d = new View3D(box3d);
      this.view3d.setWorld(world);
      this.render();
      performance.mark("replay-3d");
      resolve();
    }, 20));
    new ResizeObserver(() => this._drawLanes()).observe(this.lanes);
    this.render();
    this.map.draw();
    performance.mark("replay-2d");
  }

  toggle() {
    this.playing = !this.playing;
    this.playButton.textContent = this.playing ? "❚❚ pause" : "▶ play";
    if (this.playing) {
      if (this.t >= this.t1) this.t = this.t0;
      let last = performance.now();
      const step = (now) => {
        if (!this.playing) return;
        this.seek(Math.min(this.t1, this.t + ((now - last) / 1000) * this.speed));
        last = now;
        if (this.t >= this.t1) { this.toggle(); return; }
        requestAnimationFrame(step);
      };
      requestAnimationFrame(step);
    }
  }

  seek(t) {
    this.t = Math.max(this.t0, Math.min(this.t1, t));
    this.render();
  }

  dronesAt(t) {
    const out = [];
    for (const [id, path] of this.paths) out.push({ id, ...sampleAt(path, t) });
    return out;
  }

  trailsAt(t, drones) {
    const trails = new Map();
    for (const d of drones) {
      const p = this.paths.get(d.id);
      const trail = [];
      for (let k = 0; k <= d.index && k < p.t.length; k++) trail.push([p.x[k], p.y[k], p.t[k], p.z[k]]);
      trail.push([d.x, d.y, t, d.z]);
      trails.set(d.id, trail);
    }
    return trails;
  }

  render() {
    const drones = this.dronesAt(this.t);
    const trails = this.trailsAt(this.t, drones);
    this.map.drones = drones;
    this.map.trails = trails;
    this.map.now = this.t;
    this.map.redraw();
    if (this.view3d) this.view3d.update(drones, trails, this.map.selected);
    this.slider.value = String(Math.round((1000 * (this.t - this.t0)) / (this.t1 - this.t0)));
    this.timeLabel.textContent = `t = ${(this.t - this.t0).toFixed(1)} / ${(this.t1 - this.t0).toFixed(1)} s`;
    this._drawLanes();
  }

  _layout() {
    const ids = [...this.paths.keys()];
    const callers = ids.filter((id) => this.calls.some((c) => c.drone === id));
    const other = this.calls.some((c) => !c.drone);
    const rows = [...callers, ...(other ? ["(team)"] : [])];
    return { rows, eventH: 18, rowH: 12 };
  }

  _x(t, w) { return 60 + ((t - this.t0) / (this.t1 - this.t0)) * (w - 70); }

  _drawLanes() {
    const canvas = this.lanes, ctx = canvas.getContext("2d");
    const { rows, eventH, rowH } = this._layout();
    const w = canvas.clientWidth || 800, h = eventH + 8 + rows.length * rowH + 6;
    canvas.style.height = `${h}px`;
    const dpr = window.devicePixelRatio || 1;
    canvas.width = w * dpr; canvas.height = h * dpr;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.fillStyle = "#ffffff"; ctx.fillRect(0, 0, w, h);
    ctx.font = "10px sans-serif"; ctx.fillStyle = "#333"; ctx.textBaseline = "middle";
    ctx.fillText("events", 4, eventH / 2);
    for (const e of this.events) {
      ctx.fillStyle = EVENT_COLORS[e.kind] || "#c8ced6";
      const x = this._x(e.t, w);
      ctx.fillRect(x - 1, 2, 2, eventH - 4);
    }
    rows.forEach((row, k) => {
      const y = eventH + 8 + k * rowH;
      ctx.fillStyle = "#333"; ctx.fillText(row, 4, y + rowH / 2);
      for (const c of this.calls) {
        if ((c.drone || "(team)") !== row) continue;
        const x0 = this._x(c.t0_s, w), x1 = Math.max(x0 + 2, this._x(c.t1_s ?? c.t0_s, w));
        ctx.fillStyle = STATUS_COLORS[c.status] || "#95a5a6";
        ctx.fillRect(x0, y + 1, x1 - x0, rowH - 3);
      }
    });
    ctx.strokeStyle = "#e6007e"; ctx.lineWidth = 2;
    const xt = this._x(this.t, w);
    ctx.beginPath(); ctx.moveTo(xt, 0); ctx.lineTo(xt, h); ctx.stroke();
  }

  _timeAt(e) {
    const w = this.lanes.clientWidth;
    return this.t0 + ((e.offsetX - 60) / (w - 70)) * (this.t1 - this.t0);
  }

  _laneClick(e) { this.seek(this._timeAt(e)); }

  _laneHover(e) {
    const t = this._timeAt(e), tol = ((this.t1 - this.t0) / Math.max(1, this.lanes.clientWidth - 70)) * 4;
    const { eventH, rowH, rows } = this._layout();
    if (e.offsetY < eventH) {
      const near = this.events.filter((ev) => Math.abs(ev.t - t) <= tol).slice(0, 4);
      this.tip.textContent = near.map((ev) => `${(ev.t - this.t0).toFixed(1)} s ${ev.vehicle} ${ev.kind} ${JSON.stringify(ev.data)}`).join(" · ") || " ";
      return;
    }
    const row = rows[Math.floor((e.offsetY - eventH - 8) / rowH)];
    const call = this.calls.find((c) => (c.drone || "(team)") === row && c.t0_s - tol <= t && t <= (c.t1_s ?? c.t0_s) + tol);
    this.tip.textContent = call ? callText(call, this.t0) : " ";
  }
}

export function callText(c, t0) {
  const span = `${(c.t0_s - t0).toFixed(1)}–${((c.t1_s ?? c.t0_s) - t0).toFixed(1)} s`;
  return `#${c.i} ${c.name}(${argsText(c.args)}) → ${c.status}: ${c.message} [${span}]`;
}
