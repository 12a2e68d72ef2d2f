// The live view: the scene once, then frames over the WebSocket; 2D map, 3D view, the
// selected drone's panel, and hands-on commands for operators and admins.

import { getJson, liveSocket, postJson } from "./api.js";
import { Map2D } from "./map2d.js";
import { dronePanel, el, legend, toggleBar } from "./panel.js";
import { View3D } from "./view3d.js";
import { buildWorld } from "./world.js";

const TRAIL_POINTS = 3000;

export async function showLive(root, liveId) {
  const scene = await getJson(`/api/live/${encodeURIComponent(liveId)}/scene`);
  const world = buildWorld(scene.world);
  const state = { frame: null, drones: [], activity: {}, trails: new Map(), frames: 0, flyMode: false, pending: null };
  const status = el("span", { id: "live-status" }, "connecting…");
  const clock = el("span", { id: "sim-time" }, "t = –");
  const canvas = el("canvas", { id: "map2d" });
  const box3d = el("div", { id: "view3d" });
  const panelBox = el("div", { id: "panel-box" });
  const commandBox = el("div", { id: "commands" });
  const droneList = el("select", { id: "drone-select", size: 8, onchange: (e) => select(e.target.value) },
    world.drones.map((d) => el("option", { value: d.id }, `${d.id} — ${d.name}`)));
  root.replaceChildren(
    el("header", {}, el("h1", {}, `Live: ${scene.name}`), clock, status),
    el("main", { class: "live" },
      el("section", { class: "views" }, el("div", { class: "pane" }, canvas), el("div", { class: "pane" }, box3d)),
      el("aside", { class: "side" }, el("p", { class: "task-text", id: "live-task", hidden: scene.task ? null : "" }, scene.task || ""),
        legend(), droneList, panelBox, commandBox)));
  const map = new Map2D(canvas, { onClick: (hit) => clicked(hit) });
  root.querySelector(".side").prepend(toggleBar(map));
  map.setWorld(world);
  const view3d = new View3D(box3d);
  view3d.setWorld(world);
  window.consoleView = { map, view3d, state, world };

  function select(id) {
    map.selected = id;
    droneList.value = id;
    map.redraw();
    renderPanel();
    renderCommands();
  }

  function renderPanel() {
    const drone = state.drones.find((d) => d.id === map.selected);
    panelBox.replaceChildren(dronePanel(drone, state.activity[map.selected]));
  }

  async function send(tool, args) {
    const id = map.selected;
    state.pending = `${tool} sent to ${id}…`;
    renderCommands();
    try {
      const { body } = await postJson(`/api/live/${encodeURIComponent(liveId)}/command`, { drone_id: id, tool, args });
      state.pending = `${tool}: ${body.status} — ${body.message || body.detail || ""}`;
    } catch (error) {
      state.pending = `${tool}: refused — ${error.message}`;
    }
    renderCommands();
  }

  function renderCommands() {
    if (!scene.commands || !map.selected) { commandBox.replaceChildren(); return; }
    const alt = el("input", { id: "cmd-altitude", type: "number", value: state.altitude ?? 10, min: 1, step: 1,
      oninput: (e) => { state.altitude = Number(e.target.value); } });
    const dur = el("input", { id: "cmd-duration", type: "number", value: state.duration ?? 5, min: 1, step: 1,
      oninput: (e) => { state.duration = Number(e.target.value); } });
    const altitude = () => Number(alt.value);
    commandBox.replaceChildren(
      el("h3", {}, `Command ${map.selected}`),
      el("label", {}, "altitude (m) ", alt), el("label", {}, " hover (s) ", dur),
      el("div", { class: "buttons" },
        el("button", { id: "cmd-take_off", onclick: () => send("take_off", { altitude_m: altitude() }) }, "Take off"),
        el("button", { id: "cmd-fly", class: state.flyMode ? "active" : "",
          onclick: () => { state.flyMode = !state.flyMode; renderCommands(); } }, state.flyMode ? "Click the map…" : "Fly to (click)"),
        el("button", { id: "cmd-hover", onclick: () => send("hover", { duration_s: Number(dur.value) }) }, "Hover"),
        el("button", { id: "cmd-land", onclick: () => send("land", {}) }, "Land"),
        el("button", { id: "cmd-return_home", onclick: () => send("return_home", {}) }, "Return home")),
      el("p", { id: "cmd-result", class: "muted" }, state.pending || ""));
  }

  function clicked(hit) {
    if (state.flyMode && map.selected) {
      state.flyMode = false;
      state.flyTarget = [hit.x, hit.y];
      map.redraw();
      send("move_to", { x: +hit.x.toFixed(1), y: +hit.y.toFixed(1), z: Number(state.altitude ?? 10) });
      return;
    }
    if (hit.drone) select(hit.drone);
  }

  map.overlays.push((ctx, m, layer) => {
    if (layer !== "above" || !state.flyTarget) return;
    const [sx, sy] = m.toScreen(...state.flyTarget);
    ctx.strokeStyle = "#ffb400"; ctx.lineWidth = 2;
    ctx.beginPath(); ctx.moveTo(sx - 8, sy - 8); ctx.lineTo(sx + 8, sy + 8); ctx.moveTo(sx + 8, sy - 8); ctx.lineTo(sx - 8, sy + 8); ctx.stroke();
  });

  const taskBox = () => root.querySelector("#live-task");
  function onFrame(frame) {
    if (!frame.x || frame.x.length !== world.drones.length) return;  // not started yet
    if (frame.task !== undefined && frame.task !== taskBox().textContent) {
      taskBox().textContent = frame.task;
      taskBox().hidden = !frame.task;
    }
    if (frame.done) { status.textContent = "session finished"; status.className = "muted"; }
    state.frame = frame;
    state.frames += 1;
    state.activity = frame.act || {};
    state.drones = world.drones.map((d, k) => ({
      id: d.id, x: frame.x[k], y: frame.y[k], z: frame.z[k], yaw: frame.yaw[k], spd: frame.spd[k],
      bat: frame.bat[k], armed: !!frame.armed[k], mode: frame.mode[k],
    }));
    for (const d of state.drones) {
      let trail = state.trails.get(d.id);
      if (!trail) { trail = []; state.trails.set(d.id, trail); }
      let last = trail[trail.length - 1];
      if (last && Math.hypot(d.x - last[0], d.y - last[1]) > 50 && frame.t - last[2] < 2) {
        trail.length = 0;  // put down elsewhere by an operator reset: a new trail
        last = undefined;
      }
      if (!last || Math.hypot(d.x - last[0], d.y - last[1], d.z - last[3]) > 0.3) {
        trail.push([d.x, d.y, frame.t, d.z]);
        if (trail.length > TRAIL_POINTS) trail.shift();
      }
    }
    map.drones = state.drones;
    map.trails = state.trails;
    map.now = frame.t;
    map.redraw();
    view3d.update(state.drones, state.trails, map.selected);
    clock.textContent = `t = ${frame.t.toFixed(1)} s`;
    renderPanel();
  }

  function connect() {
    const socket = liveSocket(liveId);
    socket.onopen = () => { status.textContent = "live"; status.className = "ok"; };
    socket.onmessage = (message) => onFrame(JSON.parse(message.data));
    socket.onclose = (event) => {
      status.textContent = event.code >= 4400 ? `refused: ${event.reason}` : "disconnected, retrying…";
      status.className = "bad";
      if (event.code < 4400) setTimeout(connect, 1000);
    };
  }
  connect();
  if (world.drones.length) select(world.drones[0].id);
}
