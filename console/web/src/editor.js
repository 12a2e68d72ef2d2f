// The scenario editor: start from a blank map, a session file or a generated level; place,
// move (drag), resize (fields) and delete drones, targets and obstacles; edit tasks' text and
// budgets; every edit is validated by the server, an invalid one is shown (the entity in red)
// and the session cannot be saved until it is fixed. Every edit can be undone and redone (a
// loaded session too); a load that fails leaves the session on the page as it was. A session
// started from a shipped one or a generated level is proposed a new id (saving under a shipped
// session's id is refused: the copy's results would mix with the shipped session's). Below the
// map, the task and template editor (taskeditor.js) draws, proves and re-checks tasks.

import { getAnswer, getJson, postJson, postText } from "./api.js";
import { Map2D } from "./map2d.js";
import { navLinks } from "./nav.js";
import { el } from "./panel.js";
import { taskEditor } from "./taskeditor.js";
import { buildWorld, shapeOutline } from "./world.js";

const TARGET_KINDS = ["fixed", "moving", "waypoint", "circle", "polygon"];
const OBSTACLE_KINDS = ["circle", "point", "ellipse", "polygon"];
const LISTS = ["drones", "targets", "obstacles"];
const HISTORY = 200;  // undo steps kept

function square(x, y, half) {
  return [[x - half, y - half], [x + half, y - half], [x + half, y + half], [x - half, y + half]].map(([a, b]) => ({ x: a, y: b }));
}

function nextId(list, prefix) {
  const used = new Set(list.map((e) => e.id));
  for (let k = list.length + 1; ; k++) if (!used.has(`${prefix}${k}`)) return `${prefix}${k}`;
}

function inside([px, py], points) {
  let hit = false;
  for (let i = 0, j = points.length - 1; i < points.length; j = i++) {
    const [xi, yi] = points[i], [xj, yj] = points[j];
    if ((yi > py) !== (yj > py) && px < ((xj - xi) * (py - yi)) / (yj - yi) + xi) hit = !hit;
  }
  return hit;
}

export async function showEditor(root) {
  const state = { session: null, selected: null, problem: null, valid: false, tool: "select" };
  const status = el("p", { id: "editor-status", class: "muted" }, "");
  const props = el("div", { id: "editor-props" });
  const tasks = el("div", { id: "editor-tasks" });
  const canvas = el("canvas", { id: "map2d" });
  const pathInput = el("input", { id: "save-path", value: "sessions/custom.json", size: 28 });
  const idInput = el("input", { id: "save-id", size: 28, onchange: (e) => renameSession(e.target.value) });
  const source = el("select", { id: "start-source", onchange: () => showSourceFields() },
    ["shipped", "blank", "file", "upload", "level"].map((s) => el("option", { value: s, ...(s === "blank" ? { selected: "" } : {}) }, s)));
  const upload = el("input", { id: "start-upload", type: "file", accept: ".json,application/json" });
  const fileInput = el("input", { id: "start-path", placeholder: "session file path", size: 28 });
  const shipped = el("select", { id: "start-shipped" });
  const undoButton = el("button", { id: "undo", title: "undo (Ctrl+Z)", onclick: () => undo() }, "undo");
  const redoButton = el("button", { id: "redo", title: "redo (Ctrl+Y, Ctrl+Shift+Z)", onclick: () => redo() }, "redo");
  const history = { undo: [], redo: [] };
  let shippedIds = new Set();
  // families, levels and indices come from the server (benchmark.authoring.scenarios), filled in below
  const family = el("select", { id: "start-family" });
  const level = el("select", { id: "start-level" });
  const index = el("input", { id: "start-index", type: "number", value: 1, min: 1 });
  const toolSel = el("select", { id: "editor-tool", onchange: (e) => { state.tool = e.target.value; } },
    ["select", "add drone", ...TARGET_KINDS.map((k) => `add target ${k}`), ...OBSTACLE_KINDS.map((k) => `add obstacle ${k}`)].map((t) => el("option", { value: t }, t)));
  root.replaceChildren(
    el("header", {}, el("h1", {}, "Scenario editor"), navLinks("editor")),
    el("div", { class: "filters" }, "start from ", source, shipped, fileInput, upload, family, level, index,
      el("button", { id: "start-load", onclick: () => start() }, "load"), undoButton, redoButton),
    el("main", { class: "live" },
      el("section", { class: "views" }, el("div", { class: "pane wide" }, canvas)),
      el("aside", { class: "side" }, el("label", {}, "click to ", toolSel),
        el("button", { id: "delete-selected", onclick: () => removeSelected() }, "delete selected"),
        props, status,
        el("label", { class: "field" }, "session id ", idInput),
        el("div", { class: "buttons" }, pathInput, el("button", { id: "save", onclick: () => save() }, "save as")), tasks)));
  const map = new Map2D(canvas, { onClick: (hit) => clicked(hit), onDragStart: (xy) => dragStart(xy) });
  map.toggles.labels = true;
  map.overlays.push((ctx, m, layer) => highlight(ctx, m, layer));
  window.consoleView = { map, state, history };
  const tasksEditor = taskEditor({ state, map, record: () => record(), refresh: () => refresh() });
  map.overlays.push((ctx, m, layer) => tasksEditor.overlay(ctx, m, layer));
  root.append(tasksEditor.node);
  document.addEventListener("keydown", (e) => {
    if (!(e.ctrlKey || e.metaKey) || ["INPUT", "TEXTAREA", "SELECT"].includes(e.target.tagName)) return;
    const key = e.key.toLowerCase();
    if (key === "z" && !e.shiftKey) { e.preventDefault(); undo(); }
    else if (key === "y" || (key === "z" && e.shiftKey)) { e.preventDefault(); redo(); }
  });
  await loadChoices();
  showSourceFields();

  function showSourceFields() {
    const shown = { shipped: [shipped], file: [fileInput], upload: [upload], level: [family, level, index], blank: [] }[source.value] || [];
    for (const node of [shipped, fileInput, upload, family, level, index]) node.hidden = !shown.includes(node);
  }

  // ----------------------------------------------------------------- history
  function record() {
    if (!state.session) return;
    history.undo.push(JSON.stringify({ session: state.session, selected: state.selected }));
    if (history.undo.length > HISTORY) history.undo.shift();
    history.redo.length = 0;
    renderHistory();
  }

  function restore(from, to) {
    if (!from.length) return;
    if (state.session) to.push(JSON.stringify({ session: state.session, selected: state.selected }));
    const back = JSON.parse(from.pop());
    state.session = back.session;
    state.selected = back.selected;
    refresh(false);
    renderHistory();
  }

  function undo() { restore(history.undo, history.redo); }
  function redo() { restore(history.redo, history.undo); }

  function renderHistory() {
    undoButton.disabled = !history.undo.length;
    redoButton.disabled = !history.redo.length;
  }

  function renameSession(id) {
    if (!state.session || id === state.session.id) return;
    record();
    state.session.id = id;
    validate();
  }

  async function loadChoices() {
    try {
      const choices = await getJson("/api/editor/choices");
      const options = (names) => names.map((n) => el("option", { value: n }, n));
      family.replaceChildren(...options(choices.families));
      level.replaceChildren(...options(choices.levels));
      index.min = Math.min(...choices.indices);
      index.max = Math.max(...choices.indices);
      const listed = (await getJson("/api/editor/shipped")).sessions;
      shippedIds = new Set(listed.map((s) => s.id));
      const groups = new Map();
      for (const s of listed) {
        if (!groups.has(s.family)) groups.set(s.family, el("optgroup", { label: s.family }));
        groups.get(s.family).append(el("option", { value: s.id }, s.id));
      }
      shipped.replaceChildren(...groups.values());
    } catch (error) {
      status.textContent = `cannot list the families and levels: ${error.message}`;
      status.className = "bad";
    }
  }

  async function start() {
    // The new session replaces the one on the page only once it loaded.
    const picked = upload.files && upload.files[0];
    const what = source.value === "shipped" ? shipped.value : source.value === "file" ? fileInput.value
      : source.value === "upload" ? (picked ? picked.name : "an upload") : source.value;
    let loaded = null;
    try {
      if (source.value === "shipped") {
        const { status: code, body } = await getAnswer(`/api/editor/shipped/${encodeURIComponent(shipped.value)}`);
        if (code !== 200) throw new Error(body.detail || body.error);
        loaded = { ...body.session, id: body.proposed_id };
      } else if (source.value === "upload") {
        if (!picked) throw new Error("pick a session file first");
        const { status: code, body } = await postText("/api/editor/open", await picked.text());
        if (code !== 200) throw new Error(body.detail || body.error);
        loaded = body;
        if (shippedIds.has(loaded.id)) loaded.id = `${loaded.id}-edit`;
      } else {
        const params = new URLSearchParams({ source: source.value, path: fileInput.value, family: family.value, level: level.value, index: index.value });
        const { status: code, body } = await getAnswer(`/api/editor/start?${params}`);
        if (code !== 200) throw new Error(body.detail || body.error);
        loaded = body;
        if (source.value === "level" || shippedIds.has(loaded.id)) loaded.id = `${loaded.id}-edit`;
      }
    } catch (error) {
      status.textContent = `cannot load ${what}: ${error.message}; the session on the page is unchanged`;
      status.className = "bad";
      return;
    }
    record();
    state.session = loaded;
    state.selected = null;
    pathInput.value = `sessions/${loaded.id}.json`;
    refresh(true);
  }

  function refresh(fit = false) {
    const world = buildWorld(state.session);
    if (fit) map.setWorld(world); else { map.world = world; }
    map.drones = world.drones.map((d) => ({ ...d, yaw: 0 }));
    map.redraw();
    idInput.value = state.session.id ?? "";
    renderProps();
    renderTasks();
    validate();
    tasksEditor.worldEdited();
  }

  let pending = 0;
  async function validate() {
    const mine = ++pending;
    const { status: code, body } = await postJson("/api/editor/validate", state.session);
    if (mine !== pending) return;
    state.valid = code === 200;
    state.problem = state.valid ? null : body;
    status.textContent = state.valid ? `valid: ${body.drones} drones, ${body.targets} targets, ${body.obstacles} obstacles, ${body.tasks} tasks`
      : `invalid: ${body.error}`;
    status.className = state.valid ? "ok" : "bad";
    map.redraw();
  }

  function entity(sel) { return sel ? state.session[sel.list][sel.index] : null; }

  function hitTest([x, y]) {
    const world = map.world;
    const [px, py] = map.toScreen(x, y);
    let nearest = null, best = 10;
    world.drones.forEach((d, k) => {
      const [sx, sy] = map.toScreen(d.x, d.y);
      if (Math.hypot(sx - px, sy - py) < best) { best = Math.hypot(sx - px, sy - py); nearest = { list: "drones", index: k }; }
    });
    if (nearest) return nearest;
    for (const list of ["targets", "obstacles"]) {
      const items = world[list];
      for (let k = items.length - 1; k >= 0; k--) {
        const s = items[k].shape;
        const outline = shapeOutline(s, 32);
        const small = s.type !== "polygon" && Math.max(s.rx, s.ry) * map.view.scale < 6;
        if (inside([x, y], outline) || (small && Math.hypot(s.x - x, s.y - y) * map.view.scale < 8)) return { list, index: k };
      }
    }
    return null;
  }

  function moveBy(e, dx, dy) {
    const shift = (p) => { if (p) { p.x = +(Number(p.x) + dx).toFixed(2); p.y = +(Number(p.y) + dy).toFixed(2); } };
    const samePlace = e.home_position && e.position && e.home_position.x === e.position.x && e.home_position.y === e.position.y;
    shift(e.position);
    if (samePlace) shift(e.home_position);
    (e.vertices || []).forEach(shift);
  }

  function dragStart(xy) {
    if (!state.session || state.tool !== "select") return null;
    const hit = hitTest(xy);
    if (!hit) return null;
    state.selected = hit;
    let last = xy, recorded = false;
    return {
      move: (now) => {
        if (!recorded) { record(); recorded = true; }
        moveBy(entity(hit), now[0] - last[0], now[1] - last[1]); last = now; refreshQuiet();
      },
      end: () => refresh(),
    };
  }

  function refreshQuiet() {
    const world = buildWorld(state.session);
    map.world = world;
    map.drones = world.drones.map((d) => ({ ...d, yaw: 0 }));
  }

  function clicked(hit) {
    if (!state.session) return;
    const x = +hit.x.toFixed(1), y = +hit.y.toFixed(1);
    const s = state.session;
    if (state.tool === "select") { state.selected = hitTest([hit.x, hit.y]); renderProps(); map.redraw(); return; }
    record();
    if (state.tool === "add drone") {
      const id = nextId(s.drones, "d");
      s.drones.push({ id, name: `Drone ${id.slice(1)}`, position: { x, y, z: 0 }, max_speed: 15, max_altitude: 120, battery_capacity: 5000 });
      state.selected = { list: "drones", index: s.drones.length - 1 };
    } else if (state.tool.startsWith("add target")) {
      const kind = state.tool.split(" ")[2];
      const id = nextId(s.targets, "t");
      const t = { id, name: `${kind} ${id}`, type: kind };
      if (kind === "polygon") t.vertices = square(x, y, 25); else { t.position = { x, y, z: 0 }; t.radius = kind === "circle" ? 30 : 5; }
      if (kind === "waypoint") t.charge_amount = 25;
      s.targets.push(t);
      state.selected = { list: "targets", index: s.targets.length - 1 };
    } else if (state.tool.startsWith("add obstacle")) {
      const kind = state.tool.split(" ")[2];
      const id = nextId(s.obstacles, "o");
      const o = { id, name: `${kind} ${id}`, type: kind, height: 20 };
      if (kind === "polygon") o.vertices = square(x, y, 15);
      else { o.position = { x, y, z: 0 }; if (kind === "ellipse") { o.width = 20; o.length = 10; } else o.radius = kind === "point" ? 2 : 15; }
      s.obstacles.push(o);
      state.selected = { list: "obstacles", index: s.obstacles.length - 1 };
    }
    refresh();
  }

  function removeSelected() {
    if (!state.selected) return;
    record();
    state.session[state.selected.list].splice(state.selected.index, 1);
    state.selected = null;
    refresh();
  }

  function field(e, key, label, { sub = null, number = true } = {}) {
    const holder = sub ? e[sub] : e;
    if (!holder || !(key in holder)) return null;
    return el("label", { class: "field" }, `${label} `, el("input", { id: `prop-${sub ? `${sub}-` : ""}${key}`, value: holder[key], type: number ? "number" : "text", step: "any",
      onchange: (ev) => { record(); holder[key] = number ? Number(ev.target.value) : ev.target.value; refresh(); } }));
  }

  function renderProps() {
    const e = entity(state.selected);
    if (!e) { props.replaceChildren(el("p", { class: "muted" }, "Select an entity (click), drag to move it; or pick 'add …' and click the map.")); return; }
    props.replaceChildren(...[el("h3", {}, `${state.selected.list.slice(0, -1)} ${e.id} (${e.type || "drone"})`),
      field(e, "name", "name", { number: false }), field(e, "x", "x", { sub: "position" }), field(e, "y", "y", { sub: "position" }),
      field(e, "z", "z", { sub: "position" }), field(e, "radius", "radius (m)"), field(e, "width", "half-width x (m)"),
      field(e, "length", "half-length y (m)"), field(e, "height", "height (m, 0 = all altitudes)"),
      field(e, "max_altitude", "max altitude (m)"), field(e, "max_speed", "max speed (m/s)"),
      e.vertices ? el("label", { class: "field" }, "scale polygon ", el("input", { id: "prop-scale", type: "number", value: 1, step: 0.1, min: 0.1,
        onchange: (ev) => { record(); scalePolygon(e, Number(ev.target.value)); refresh(); } })) : null].filter(Boolean));
  }

  function scalePolygon(e, factor) {
    if (!(factor > 0)) return;
    const cx = e.vertices.reduce((a, v) => a + Number(v.x), 0) / e.vertices.length;
    const cy = e.vertices.reduce((a, v) => a + Number(v.y), 0) / e.vertices.length;
    for (const v of e.vertices) { v.x = +(cx + (v.x - cx) * factor).toFixed(2); v.y = +(cy + (v.y - cy) * factor).toFixed(2); }
  }

  function renderTasks() {
    const list = state.session.tasks || [];
    tasks.replaceChildren(el("h3", {}, `Tasks (${list.length})`), ...list.map((t, k) => el("div", { class: "task-edit" },
      el("b", {}, t.id), el("textarea", { id: `task-text-${k}`, rows: 2, onchange: (ev) => { record(); t.text = ev.target.value; validate(); } }, t.text || ""),
      el("label", {}, "tool calls ", el("input", { id: `task-calls-${k}`, type: "number", value: t.budget?.tool_calls ?? 0,
        onchange: (ev) => { record(); t.budget = { ...t.budget, tool_calls: Number(ev.target.value) }; validate(); } })),
      el("label", {}, " sim s ", el("input", { id: `task-sim-${k}`, type: "number", value: t.budget?.sim_time_s ?? 0,
        onchange: (ev) => { record(); t.budget = { ...t.budget, sim_time_s: Number(ev.target.value) }; validate(); } })),
      el("div", { class: "task-proof" }, tasksEditor.taskControls(k)))));
  }

  function highlight(ctx, m, layer) {
    if (layer !== "above" || !m.world) return;
    const mark = (sel, color) => {
      if (!sel || !LISTS.includes(sel.list)) return;
      const item = m.world[sel.list][sel.index];
      if (!item) return;
      ctx.strokeStyle = color; ctx.lineWidth = 3;
      if (sel.list === "drones") { const [sx, sy] = m.toScreen(item.x, item.y); ctx.beginPath(); ctx.arc(sx, sy, 11, 0, 2 * Math.PI); ctx.stroke(); return; }
      ctx.beginPath();
      shapeOutline(item.shape, 48).forEach(([x, y], k) => { const [sx, sy] = m.toScreen(x, y); k ? ctx.lineTo(sx, sy) : ctx.moveTo(sx, sy); });
      ctx.closePath(); ctx.stroke();
    };
    mark(state.selected, "#ffb400");
    if (state.problem?.entity) mark(state.problem.entity, "#d90429");
  }

  async function save() {
    await validate();
    if (!state.valid) { status.textContent = `not saved: ${state.problem?.error}`; status.className = "bad"; return; }
    const { status: code, body } = await postJson("/api/editor/save", { path: pathInput.value, session: state.session });
    status.textContent = code === 200 ? `saved to ${body.path}` : `not saved: ${body.error}`;
    status.className = code === 200 ? "ok" : "bad";
  }

  await start();
  history.undo.length = 0;  // the first (blank) map is where history starts
  renderHistory();
}
