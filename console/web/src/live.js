// The live view: the scene once, then frames over the WebSocket; 2D map, 3D view, the drone
// list (each drone's state, the command it carries out and its last outcome under it), the
// focused drone's panel, and hands-on commands for operators and admins: for the drones picked
// in the list or on the map (shift-click adds one), or all of them.

import { getJson, liveSocket, postJson } from "./api.js";
import { Map2D } from "./map2d.js";
import { argsText, dronePanel, el, fmt, legend, toggleBar } from "./panel.js";
import { View3D } from "./view3d.js";
import { buildWorld } from "./world.js";

const TRAIL_POINTS = 3000;
const GOOD = new Set(["ok", "accepted"]);
const REFUSAL_POLL_MS = 3000;  // how often the page asks whether commands are refused now

export async function showLive(root, liveId) {
  const scene = await getJson(`/api/live/${encodeURIComponent(liveId)}/scene`);
  const world = buildWorld(scene.world);
  const state = {
    frame: null, drones: [], activity: {}, trails: new Map(), frames: 0, flyMode: false, pending: null,
    markers: new Map(),  // drone -> {x, y, command}: fly-to targets the drones accepted
    refusal: null,  // why no command may run now (a benchmark task runs), from the server
  };
  const status = el("span", { id: "live-status" }, "connecting…");
  const clock = el("span", { id: "sim-time" }, "t = –");
  const canvas = el("canvas", { id: "map2d" });
  const box3d = el("div", { id: "view3d" });
  const panelBox = el("div", { id: "panel-box" });
  const commandBox = el("div", { id: "commands" });
  const rows = new Map();
  const droneList = el("ul", { id: "drone-list" }, world.drones.map((d) => {
    const pick = el("input", { type: "checkbox", class: "pick", "data-drone": d.id, hidden: scene.commands ? null : "",
      onchange: (e) => { if (e.target.checked) map.chosen.add(d.id); else map.chosen.delete(d.id); changed(); } });
    const row = el("li", { class: "drone-row", "data-drone": d.id },
      el("div", { class: "drone-head" }, pick,
        el("a", { href: "#", class: "drone-id", onclick: (e) => { e.preventDefault(); focus(d.id); } }, d.id),
        el("span", { class: "drone-state muted" }, "")),
      el("div", { class: "drone-executing muted" }, ""),
      el("div", { class: "drone-outcome" }, ""));
    rows.set(d.id, { row, pick });
    return row;
  }));
  root.replaceChildren(
    el("header", {}, el("h1", {}, `Live: ${scene.name}`), clock, status),
    el("main", { class: "live" },
      el("section", { class: "views" }, el("div", { class: "pane" }, canvas), el("div", { class: "pane" }, box3d)),
      el("aside", { class: "side" }, el("p", { class: "task-text", id: "live-task", hidden: scene.task ? null : "" }, scene.task || ""),
        legend(), commandBox,
        el("div", { class: "buttons", hidden: scene.commands ? null : "" }, el("button", { id: "pick-all", onclick: () => pickAll(true) }, "select all"),
          el("button", { id: "pick-none", onclick: () => pickAll(false) }, "select none")),
        droneList, panelBox)));
  const map = new Map2D(canvas, { onClick: (hit) => clicked(hit) });
  root.querySelector(".side").prepend(toggleBar(map));
  map.setWorld(world);
  const view3d = new View3D(box3d);
  view3d.setWorld(world);
  window.consoleView = { map, view3d, state, world };

  function focus(id, add = false) {
    map.selected = id;
    if (!add) map.chosen.clear();
    if (add && map.chosen.has(id) && map.chosen.size > 1) map.chosen.delete(id);
    else map.chosen.add(id);
    changed();
  }

  function pickAll(on) {
    map.chosen = new Set(on ? world.drones.map((d) => d.id) : []);
    changed();
  }

  function chosen() { return world.drones.map((d) => d.id).filter((id) => map.chosen.has(id)); }

  function changed() {
    for (const [id, { row, pick }] of rows) {
      pick.checked = map.chosen.has(id);
      row.classList.toggle("focused", id === map.selected);
    }
    map.redraw();
    renderPanel();
    renderCommands();
  }

  function renderPanel() {
    const drone = state.drones.find((d) => d.id === map.selected);
    panelBox.replaceChildren(dronePanel(drone, state.activity[map.selected]));
  }

  function outcomeText(last) {
    return last ? `${last.name}: ${last.status} — ${last.message}` : "";
  }

  function renderRows() {
    // Each frame: only the texts that changed are touched (a big swarm has a long list).
    const put = (node, text, cls = null) => {
      if (node.textContent !== text) node.textContent = text;
      if (cls !== null && node.className !== cls) node.className = cls;
    };
    for (const d of state.drones) {
      const { row } = rows.get(d.id);
      const act = state.activity[d.id] || {};
      put(row.querySelector(".drone-state"), ` ${d.mode ?? "–"} · ${fmt(d.z, 1, " m")} · ${fmt(d.bat, 0, " %")}`);
      put(row.querySelector(".drone-executing"), act.executing ? `▶ ${act.executing.name}(${argsText(act.executing.args)})` : "");
      put(row.querySelector(".drone-outcome"), outcomeText(act.last), `drone-outcome status-${act.last ? act.last.status : "none"}`);
    }
  }

  async function send(tool, args, argsByDrone = null) {
    const ids = chosen();
    if (!ids.length) {
      state.pending = "select a drone first (click it on the map or tick it in the list)";
      state.pendingClass = "bad";
      renderCommands();
      return {};
    }
    return sendTo(ids, tool, args, argsByDrone);
  }

  async function sendTo(ids, tool, args, argsByDrone = null) {
    state.pending = `${tool} sent to ${ids.join(", ")}…`;
    state.pendingClass = "muted";
    renderCommands();
    const path = `/api/live/${encodeURIComponent(liveId)}/command`;
    let results = {};
    try {
      const body = ids.length === 1 ? { drone_id: ids[0], tool, args: (argsByDrone && argsByDrone[ids[0]]) || args }
        : { drone_ids: ids, tool, args, ...(argsByDrone ? { args_by_drone: argsByDrone } : {}) };
      const { body: answer } = await postJson(path, body);
      results = ids.length === 1 ? { [ids[0]]: answer } : (answer.results || {});
      if (!answer.results && ids.length > 1) throw new Error(answer.message || answer.detail || "no results");
      const parts = Object.entries(results).map(([id, r]) => (ids.length === 1 ? `${r.status} — ${r.message || ""}` : `${id} ${r.status}${GOOD.has(r.status) ? "" : ` (${r.message})`}`));
      state.pending = `${tool}: ${parts.join("; ")}`;
      state.pendingClass = Object.values(results).every((r) => GOOD.has(r.status)) ? "ok" : "bad";
    } catch (error) {
      state.pending = `${tool}: refused — ${error.message}`;
      state.pendingClass = "bad";
      if (error.status === 409) checkRefusal();
    }
    for (const [id, r] of Object.entries(results)) {
      if (GOOD.has(r.status) && tool !== "move_to") state.markers.delete(id);  // a new goal
    }
    renderCommands();
    map.redraw();
    return results;
  }

  async function flyTo(x, y) {
    // A selection keeps its shape: each drone flies to the point plus its offset from the
    // selection's centre.
    const ids = chosen();
    if (!ids.length) return;
    const at = new Map(state.drones.map((d) => [d.id, d]));
    const here = ids.map((id) => at.get(id)).filter(Boolean);
    const cx = here.reduce((a, d) => a + d.x, 0) / Math.max(1, here.length);
    const cy = here.reduce((a, d) => a + d.y, 0) / Math.max(1, here.length);
    const z = Number(state.altitude ?? 10);
    const targets = {};
    for (const id of ids) {
      const d = at.get(id);
      const [ox, oy] = d && ids.length > 1 ? [d.x - cx, d.y - cy] : [0, 0];
      targets[id] = { x: +(x + ox).toFixed(1), y: +(y + oy).toFixed(1), z };
    }
    const results = await sendTo(ids, "move_to", targets[ids[0]], targets);
    for (const [id, r] of Object.entries(results)) {
      if (GOOD.has(r.status)) state.markers.set(id, { x: targets[id].x, y: targets[id].y, command: r.command });
      else state.markers.delete(id);
    }
    map.redraw();
  }

  function renderCommands() {
    if (!scene.commands) { commandBox.replaceChildren(); return; }
    const ids = chosen();
    const alt = el("input", { id: "cmd-altitude", type: "number", value: state.altitude ?? 10, min: 1, step: 1,
      oninput: (e) => { state.altitude = Number(e.target.value); } });
    const dur = el("input", { id: "cmd-duration", type: "number", value: state.duration ?? 5, min: 1, step: 1,
      oninput: (e) => { state.duration = Number(e.target.value); } });
    const altitude = () => Number(alt.value);
    const off = state.refusal ? "" : null;  // every command button, while commands are refused
    const who = ids.length === 0 ? "no drone selected" : ids.length === world.drones.length && ids.length > 1
      ? `all ${ids.length} drones` : ids.length > 4 ? `${ids.length} drones` : ids.join(", ");
    commandBox.replaceChildren(...[
      el("h3", { id: "cmd-target" }, `Command: ${who}`),
      state.refusal ? el("p", { id: "cmd-refusal", class: "note" }, `Commands are refused now: ${state.refusal}`) : null,
      el("div", { class: "buttons" },
        el("button", { id: "cmd-hold", class: "stop", disabled: ids.length && !state.refusal ? null : "", onclick: () => send("hold", {}) }, "Stop / Hold"),
        el("button", { id: "cmd-hold-all", class: "stop", disabled: off, onclick: () => sendTo(world.drones.map((d) => d.id), "hold", {}) }, "Hold all")),
      el("label", {}, "altitude (m) ", alt), el("label", {}, " hover (s) ", dur),
      el("div", { class: "buttons" },
        el("button", { id: "cmd-take_off", disabled: off, onclick: () => send("take_off", { altitude_m: altitude() }) }, "Take off"),
        el("button", { id: "cmd-fly", disabled: off, class: state.flyMode ? "active" : "",
          onclick: () => { state.flyMode = !state.flyMode; renderCommands(); } }, state.flyMode ? "Click the map…" : "Fly to (click)"),
        el("button", { id: "cmd-hover", disabled: off, onclick: () => send("hover", { duration_s: Number(dur.value) }) }, "Hover"),
        el("button", { id: "cmd-land", disabled: off, onclick: () => send("land", {}) }, "Land"),
        el("button", { id: "cmd-return_home", disabled: off, onclick: () => send("return_home", {}) }, "Return home")),
      el("p", { id: "cmd-result", class: state.pendingClass || "muted" }, state.pending || "")].filter(Boolean));
  }

  function clicked(hit) {
    if (state.flyMode && chosen().length) {
      state.flyMode = false;
      renderCommands();
      flyTo(hit.x, hit.y);
      return;
    }
    if (hit.drone) focus(hit.drone, hit.event && (hit.event.shiftKey || hit.event.ctrlKey || hit.event.metaKey));
  }

  map.overlays.push((ctx, m, layer) => {
    if (layer !== "above") return;
    for (const [id, mark] of state.markers) {
      const [sx, sy] = m.toScreen(mark.x, mark.y);
      ctx.strokeStyle = "#ffb400"; ctx.lineWidth = 2;
      ctx.beginPath(); ctx.moveTo(sx - 8, sy - 8); ctx.lineTo(sx + 8, sy + 8); ctx.moveTo(sx + 8, sy - 8); ctx.lineTo(sx - 8, sy + 8); ctx.stroke();
      if (state.markers.size > 1) {
        ctx.font = "10px sans-serif"; ctx.fillStyle = "#8a6100"; ctx.textAlign = "left"; ctx.textBaseline = "top";
        ctx.fillText(id, sx + 9, sy + 2);
      }
    }
  });

  function dropFinishedMarkers() {
    // A fly-to that ended other than ok (refused late, replaced, blocked) takes its marker.
    for (const [id, mark] of state.markers) {
      const act = state.activity[id] || {};
      const running = act.executing && act.executing.id === mark.command;
      if (!running && act.last && act.last.id === mark.command && act.last.status !== "ok") state.markers.delete(id);
      if (act.executing && act.executing.id !== undefined && act.executing.id > mark.command) state.markers.delete(id);
    }
  }

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
    state.drones = world.drones.map((d, k) => {
      const last = state.activity[d.id]?.last;
      return {
        id: d.id, x: frame.x[k], y: frame.y[k], z: frame.z[k], yaw: frame.yaw[k], spd: frame.spd[k],
        bat: frame.bat[k], armed: !!frame.armed[k], mode: frame.mode[k],
        outcome: last ? { text: `${last.name}: ${last.status}`, status: last.status } : null,
      };
    });
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
    dropFinishedMarkers();
    map.drones = state.drones;
    map.trails = state.trails;
    map.now = frame.t;
    map.redraw();
    view3d.update(state.drones, state.trails, map.selected);
    clock.textContent = `t = ${frame.t.toFixed(1)} s`;
    renderPanel();
    renderRows();
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
  async function checkRefusal() {
    // Whether commands are refused now (a benchmark task runs): said up front, buttons greyed.
    try {
      const { refusal } = await getJson(`/api/live/${encodeURIComponent(liveId)}/commands`);
      if (refusal !== state.refusal) { state.refusal = refusal; renderCommands(); }
    } catch { /* the next poll tries again */ }
  }

  connect();
  if (scene.commands) { checkRefusal(); setInterval(checkRefusal, REFUSAL_POLL_MS); }
  if (world.drones.length) focus(world.drones[0].id);
  else changed();
}
