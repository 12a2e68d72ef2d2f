// The scenario editor's task and template editor: pick a template file (built-in or saved) or
// write one, validate it (the field to blame is named), draw its tasks on the world being
// edited (the entities and points each task names are highlighted on the map, its check tree
// shown), add them to the session, prove one with the oracle (a sandbox swarm the server flies;
// its live frames move the drones on the map, then the recorded window plays back), re-check
// every task whenever the world is edited (which are still solvable, which leaf fails), and
// save a template into the editor's save folder.

import { getJson, liveSocket, pageUrl, postJson } from "./api.js";
import { checkTree } from "./checks.js";
import { el } from "./panel.js";
import { decodePaths, sampleAt } from "./replay.js";
import { shapeOutline } from "./world.js";

const DRAWN = "#00a3a3";     // entities and points of drawn tasks
const CHOSEN = "#7b2cbf";    // those of the task picked
const POLL_MS = 400;         // a proof's status is asked this often while it flies
const PLAYBACK_S = 6;        // a proof's recorded window plays back in this many seconds
const RECHECK_MS = 400;      // a re-check waits this long after the last edit
// what "new" puts in the text box: a small template to start writing from
const SKELETON = {
  format: "mavswarm.template/1", id: "my_template", category: "navigation", difficulty: "easy",
  entities: [{ group: "drone_1", kind: "drone" }],
  values: [{ name: "alt", kind: "int", min: 10, max: 25 }, { name: "p", kind: "point" }],
  phrasings: ["Fly {drone_1_name} to {p} at {alt} m and land there."],
  checks: { logic: "and", checks: [
    { endpoint: "drone_has_visited_position", parameters: { drone_id: "{drone_1_id}", x: "{p.x}", y: "{p.y}", z: "{alt}", tolerance: 3.0 } },
    { endpoint: "drone_on_ground", parameters: { drone_id: "{drone_1_id}" } }] },
  budget: { steps: 3, flight_diagonals: 1 },
};

function paramText(parameters) {
  return Object.entries(parameters || {}).map(([k, v]) => `${k}=${typeof v === "object" ? JSON.stringify(v) : v}`).join(", ");
}

// The check tree as nested lists: groups by their logic, leaves by endpoint and parameters.
export function treeView(node, path = "checks") {
  if (node && node.endpoint) {
    return el("li", { class: "leaf", "data-path": path }, el("b", {}, node.endpoint.replaceAll("_", " ")),
      node.expect === false ? " (must not hold)" : "", el("div", { class: "params muted" }, paramText(node.parameters)));
  }
  return el("li", { class: "group", "data-path": path }, el("b", {}, (node?.logic || "and").toUpperCase()),
    el("ul", {}, (node?.checks || []).map((child, k) => treeView(child, `${path}[${k}]`))));
}

export function taskEditor({ state, map, record, refresh }) {
  const te = { templates: [], drawn: [], chosen: null, recheck: null, proof: null, playing: null };
  const pick = el("select", { id: "template-pick" });
  const text = el("textarea", { id: "template-text", rows: 14, spellcheck: "false", placeholder: "a template file (mavswarm.template/1)" });
  const count = el("input", { id: "template-count", type: "number", value: 2, min: 1, max: 20, size: 3 });
  const seed = el("input", { id: "template-seed", type: "number", value: 1, min: 0, size: 6 });
  const status = el("p", { id: "template-status", class: "muted" }, "");
  const drawnBox = el("div", { id: "drawn-tasks" });
  const recheckBox = el("p", { id: "recheck-status", class: "muted" }, "");
  const proofBox = el("div", { id: "proof" });
  const node = el("section", { id: "task-editor", class: "task-editor" },
    el("h2", {}, "Tasks and templates"),
    el("div", { class: "filters" }, "template ", pick, el("button", { id: "template-load", onclick: () => loadTemplate() }, "open"),
      el("button", { id: "template-new", onclick: () => newTemplate() }, "new"),
      " tasks ", count, " seed ", seed,
      el("button", { id: "template-validate", onclick: () => validate() }, "validate"),
      el("button", { id: "template-draw", onclick: () => draw() }, "draw on the map"),
      el("button", { id: "template-save", onclick: () => saveTemplate() }, "save template")),
    text, status, drawnBox,
    el("div", { class: "buttons" }, el("button", { id: "tasks-recheck", onclick: () => recheck() }, "re-check every task"), recheckBox),
    proofBox);
  window.consoleView.tasks = te;

  function say(box, message, cls) { box.textContent = message; box.className = cls; }

  async function listTemplates() {
    try {
      te.templates = (await getJson("/api/editor/templates")).templates;
      const groups = new Map();
      for (const t of te.templates) {
        if (!groups.has(t.source)) groups.set(t.source, el("optgroup", { label: t.source }));
        groups.get(t.source).append(el("option", { value: t.id }, t.error ? `${t.id} (does not load)` : `${t.id} — ${t.category}`));
      }
      pick.replaceChildren(...groups.values());
    } catch (error) {
      say(status, `cannot list the templates: ${error.message}`, "bad");
    }
  }

  async function loadTemplate() {
    try {
      const found = await getJson(`/api/editor/templates/${encodeURIComponent(pick.value)}`);
      text.value = found.text;
      say(status, `opened ${found.id} (${found.source})`, "muted");
    } catch (error) {
      say(status, `cannot open ${pick.value}: ${error.message}`, "bad");
    }
  }

  function newTemplate() {
    text.value = `${JSON.stringify(SKELETON, null, 2)}\n`;
    say(status, "a new template: edit it, validate, draw it on the map, save it", "muted");
  }

  function refusal(body) { return body.field ? `${body.field}: ${body.error}` : (body.error || body.detail); }

  async function validate() {
    const { status: code, body } = await postJson("/api/editor/templates/validate", { text: text.value });
    if (code === 200) say(status, `valid template ${body.id} (${body.category}, ${body.phrasings} phrasings)`, "ok");
    else say(status, `invalid template: ${refusal(body)}`, "bad");
    return code === 200;
  }

  async function draw() {
    if (!state.session) return;
    const { status: code, body } = await postJson("/api/editor/templates/instantiate",
      { session: state.session, text: text.value, count: Number(count.value), seed: Number(seed.value) });
    if (code !== 200) { say(status, `cannot draw: ${refusal(body)}`, "bad"); te.drawn = []; renderDrawn(); return; }
    te.drawn = body.tasks;
    te.chosen = te.drawn.length ? 0 : null;
    const unfit = body.unfit.length ? `; ${body.unfit.length} draws did not fit: ${body.unfit.join("; ")}` : "";
    say(status, `drew ${te.drawn.length} tasks of ${body.template}${body.note ? ` (${body.note})` : ""}${unfit}`, "ok");
    renderDrawn();
    map.redraw();
  }

  function entityLine(entities) {
    const parts = ["drones", "targets", "obstacles"].filter((k) => entities[k].length).map((k) => `${k}: ${entities[k].join(", ")}`);
    if (entities.points.length) parts.push(`points: ${entities.points.map(([x, y]) => `(${x}, ${y})`).join(" ")}`);
    return parts.join("; ") || "no entity named";
  }

  function renderDrawn() {
    drawnBox.replaceChildren(...te.drawn.map((d, k) => el("div", { class: `drawn-task${k === te.chosen ? " chosen" : ""}`, id: `drawn-${k}`,
      onclick: () => { te.chosen = k; renderDrawn(); map.redraw(); } },
      el("b", {}, `${d.task.id} `), d.task.text,
      el("div", { class: "muted entities", id: `drawn-entities-${k}` }, entityLine(d.entities)),
      el("div", { id: `drawn-check-${k}`, class: d.check.solvable ? "ok" : "bad" }, checkText(d.check)),
      el("ul", { class: "checks", id: `drawn-tree-${k}` }, treeView(d.tree)))),
    ...(te.drawn.length ? [el("button", { id: "drawn-add", onclick: () => addDrawn() }, `add ${te.drawn.length} tasks to the session`)] : []));
  }

  function addDrawn() {
    record();
    state.session.tasks = [...(state.session.tasks || []), ...te.drawn.map((d) => d.task)];
    say(status, `added ${te.drawn.length} tasks to the session`, "ok");
    te.drawn = [];
    te.chosen = null;
    renderDrawn();
    refresh();
  }

  async function saveTemplate() {
    const { status: code, body } = await postJson("/api/editor/templates/save", { text: text.value });
    if (code === 200) { say(status, `saved template ${body.id} to ${body.path}`, "ok"); await listTemplates(); pick.value = body.id; }
    else say(status, `template not saved: ${refusal(body)}`, "bad");
  }

  // ------------------------------------------------------------------ re-checking
  let recheckTimer = null, rechecks = 0;
  function worldEdited() {
    clearTimeout(recheckTimer);
    if (!state.session || !(state.session.tasks || []).length) { te.recheck = null; say(recheckBox, "", "muted"); return; }
    recheckTimer = setTimeout(() => recheck(), RECHECK_MS);
  }

  async function recheck() {
    if (!state.session) return;
    const mine = ++rechecks;
    const { status: code, body } = await postJson("/api/editor/tasks/recheck", { session: state.session });
    if (mine !== rechecks) return;
    if (code !== 200) { te.recheck = null; say(recheckBox, `cannot re-check: ${refusal(body)}`, "bad"); return; }
    te.recheck = body;
    say(recheckBox, `re-check: ${body.solvable} of ${body.total} tasks solvable`, body.solvable === body.total ? "ok" : "bad");
    for (const r of body.tasks) {
      const spot = document.getElementById(`task-check-${r.index}`);
      if (spot) spot.replaceWith(checkNote(r.index));
    }
  }

  function checkText(r) {
    return r.solvable ? "solvable" : `unsolvable: ${r.leaf ? `${r.leaf} (${r.endpoint}): ` : ""}${r.reason}`;
  }

  function checkNote(k) {
    const r = te.recheck?.tasks?.[k];
    if (!r) return el("span", { id: `task-check-${k}`, class: "muted" }, "");
    return el("span", { id: `task-check-${k}`, class: r.solvable ? "ok" : "bad" }, checkText(r));
  }

  // ------------------------------------------------------------------ proving
  async function prove(k) {
    const task = state.session.tasks[k];
    const { status: code, body } = await postJson("/api/editor/proofs", { session: state.session, task_id: task.id });
    if (code !== 202) { proofBox.replaceChildren(el("p", { id: "proof-status", class: "bad" }, `cannot prove ${task.id}: ${refusal(body)}`)); return; }
    te.proof = body;
    stopPlayback();
    const socket = liveSocket(body.live);
    socket.onmessage = (message) => flyFrame(JSON.parse(message.data));
    proofBox.replaceChildren(el("p", { id: "proof-status", class: "muted" }, `proving ${task.id} with the oracle (${body.id}) … `,
      el("a", { href: pageUrl(`/live/${encodeURIComponent(body.live)}`), target: "_blank" }, "live view")));
    let proof = body;
    while (proof.status === "running") {
      await new Promise((resolve) => setTimeout(resolve, POLL_MS));
      proof = await getJson(`/api/editor/proofs/${encodeURIComponent(body.id)}`);
    }
    socket.close();
    te.proof = proof;
    showProof(task, proof);
  }

  function flyFrame(frame) {
    if (!frame.x || !map.world || frame.x.length !== map.world.drones.length) return;
    map.drones = map.world.drones.map((d, k) => ({ ...d, x: frame.x[k], y: frame.y[k], z: frame.z[k], yaw: frame.yaw[k] }));
    map.redraw();
  }

  function showProof(task, proof) {
    const r = proof.record;
    const line = proof.status === "error" || !r ? `${task.id}: the proof could not fly: ${proof.error}`
      : `${task.id} ${proof.status}: ${r.checks_passed}/${r.checks_total} checks, ${r.tool_calls} tool calls, ${r.sim_time_s} s simulated (${r.finish}${r.error ? `: ${r.error}` : ""}; flight ${proof.tries})`;
    proofBox.replaceChildren(el("p", { id: "proof-status", class: proof.status === "passed" ? "ok" : "bad" }, line),
      ...(r ? [checkTree(r, task.checks)] : []),
      ...(r?.replay ? [el("button", { id: "proof-replay", onclick: () => playBack(r.replay) }, "play the flight again")] : []));
    if (r?.replay) playBack(r.replay);
  }

  function playBack(replay) {
    stopPlayback();
    const paths = decodePaths(replay.paths, replay.t0_s);
    const span = Math.max(0.1, replay.t1_s - replay.t0_s);
    const start = performance.now();
    const step = () => {
      const f = Math.min(1, (performance.now() - start) / (PLAYBACK_S * 1000));
      const t = replay.t0_s + f * span;
      map.drones = map.world.drones.map((d) => {
        const path = paths.get(d.id);
        return path ? { ...d, ...sampleAt(path, t) } : { ...d, yaw: 0 };
      });
      map.redraw();
      te.playing = f < 1 ? requestAnimationFrame(step) : null;
      if (!te.playing) te.played = (te.played || 0) + 1;
    };
    te.playing = requestAnimationFrame(step);
  }

  function stopPlayback() { if (te.playing) cancelAnimationFrame(te.playing); te.playing = null; }

  // ------------------------------------------------------------------ the map
  function overlay(ctx, m, layer) {
    if (layer !== "above" || !m.world) return;
    te.drawn.forEach((d, k) => mark(ctx, m, d.entities, k === te.chosen ? CHOSEN : DRAWN, k === te.chosen ? 3 : 2));
  }

  function mark(ctx, m, entities, color, width) {
    ctx.strokeStyle = color; ctx.fillStyle = color; ctx.lineWidth = width;
    ctx.setLineDash([6, 4]);
    for (const list of ["targets", "obstacles"]) {
      for (const id of entities[list]) {
        const item = m.world[list].find((e) => e.id === id);
        if (!item) continue;
        ctx.beginPath();
        shapeOutline(item.shape, 48).forEach(([x, y], i) => { const [sx, sy] = m.toScreen(x, y); i ? ctx.lineTo(sx, sy) : ctx.moveTo(sx, sy); });
        ctx.closePath(); ctx.stroke();
      }
    }
    ctx.setLineDash([]);
    for (const id of entities.drones) {
      const d = m.world.drones.find((e) => e.id === id);
      if (!d) continue;
      const [sx, sy] = m.toScreen(d.x, d.y);
      ctx.beginPath(); ctx.arc(sx, sy, 14, 0, 2 * Math.PI); ctx.stroke();
    }
    for (const [x, y] of entities.points) {
      const [sx, sy] = m.toScreen(x, y);
      ctx.beginPath(); ctx.moveTo(sx - 7, sy - 7); ctx.lineTo(sx + 7, sy + 7); ctx.moveTo(sx + 7, sy - 7); ctx.lineTo(sx - 7, sy + 7); ctx.stroke();
    }
  }

  // the controls the session's task list shows for task k
  function taskControls(k) {
    return [el("button", { id: `task-prove-${k}`, onclick: () => prove(k) }, "prove"), " ", checkNote(k)];
  }

  listTemplates();
  return { node, overlay, worldEdited, taskControls, prove, stopPlayback };
}
