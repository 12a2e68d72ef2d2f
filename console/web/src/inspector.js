// The run inspector: runs -> tasks (filterable), a task's page (text, replay of its window, the
// agent's tool calls on the same timeline, an LLM agent's transcript under it (transcript.js),
// the check tree); the compare view is in compare.js.

import { getJson, pageUrl } from "./api.js";
import { checkTree, coverageOverlay } from "./checks.js";
import { navLinks } from "./nav.js";
import { el, fmt } from "./panel.js";
import { ReplayPlayer, callText } from "./replay.js";
import { transcriptPanel } from "./transcript.js";
import { buildWorld } from "./world.js";

export { showCompare } from "./compare.js";

const FILTERS = ["family", "level", "category", "template", "agent"];

export async function showRuns(root, runId) {
  const info = await getJson("/api/info");
  const runs = info.runs;
  if (!runs.length) { root.replaceChildren(el("p", {}, "No results folders were opened.")); return; }
  runId = runId || runs[0].id;
  const data = await getJson(`/api/runs/${encodeURIComponent(runId)}/tasks`);
  const rows = data.rows;
  const chosen = {};
  const table = el("table", { class: "tasks", id: "task-table" });
  const count = el("span", { id: "task-count" });
  const options = (field) => [...new Set(rows.map((r) => r[field]))].filter((v) => v !== null && v !== undefined).sort();
  const select = (field, values) => el("label", {}, `${field} `, el("select", { id: `filter-${field}`, onchange: (e) => { chosen[field] = e.target.value; render(); } },
    el("option", { value: "" }, "all"), values.map((v) => el("option", { value: v }, v))));
  const endpoints = [...new Set(rows.flatMap((r) => r.endpoints))].sort();
  const filters = el("div", { class: "filters" }, FILTERS.map((f) => select(f, options(f))), select("endpoint", endpoints),
    select("verdict", ["pass", "fail"]));
  function keep(r) {
    for (const f of FILTERS) if (chosen[f] && String(r[f]) !== chosen[f]) return false;
    if (chosen.endpoint && !r.endpoints.includes(chosen.endpoint)) return false;
    if (chosen.verdict && (chosen.verdict === "pass") !== !!r.passed) return false;
    return true;
  }
  function render() {
    const shown = rows.filter(keep);
    count.textContent = `${shown.length} of ${rows.length} tasks, ${shown.filter((r) => r.passed).length} passed`;
    table.replaceChildren(
      el("tr", {}, ["session", "task", "trial", "agent", "template", "verdict", "checks", "failed endpoints", "calls", "sim s", "replay"].map((h) => el("th", {}, h))),
      ...shown.map((r) => el("tr", { class: r.passed ? "pass" : "fail" },
        el("td", {}, r.session), el("td", {}, el("a", { href: pageUrl(`/inspect/${r.session}/${r.task}`, { trial: r.trial, run: runId, agent: r.agent }) }, r.task)),
        el("td", {}, r.trial), el("td", {}, r.agent), el("td", {}, r.template), el("td", { class: "verdict" }, r.passed ? "PASS" : `FAIL${r.finish !== "finished" ? ` (${r.finish})` : ""}`),
        el("td", {}, `${r.checks_passed}/${r.checks_total}`), el("td", {}, r.failed_endpoints.join(", ")),
        el("td", {}, r.tool_calls), el("td", {}, fmt(r.sim_time_s, 0)), el("td", {}, r.has_replay ? "yes" : "–"))));
  }
  const runLinks = el("div", { class: "runs" }, runs.map((r) => el("a", { href: pageUrl(`/runs/${r.id}`), class: r.id === runId ? "current" : "" },
    `${r.id} (${r.agents.join(", ")}: ${r.passed}/${r.tasks} passed)`)),
    runs.length > 1 || runs[0].agents.length > 1 ? el("a", { href: pageUrl("/compare") }, "compare two runs…") : null,
    el("a", { href: pageUrl("/leaderboard") }, "leaderboard"));
  root.replaceChildren(el("header", {}, el("h1", {}, `Runs — ${runId}`), navLinks("runs")), runLinks, filters, count, table);
  render();
}

export async function showTask(root, sessionId, taskId, params) {
  const query = new URLSearchParams({ trial: params.get("trial") || "0" });
  for (const k of ["run", "agent"]) if (params.get(k)) query.set(k, params.get(k));
  const view = await getJson(`/api/task/${encodeURIComponent(sessionId)}/${encodeURIComponent(taskId)}?${query}`);
  const record = view.record, replay = view.replay;
  const task = replay?.task || {};
  const verdict = el("span", { id: "verdict", class: record.passed ? "ok" : "bad" }, record.passed ? "PASS" : "FAIL");
  const facts = `${record.agent} · trial ${record.trial} · finish ${record.finish} · ${record.checks_passed}/${record.checks_total} checks · ` +
    `${record.tool_calls} tool calls · ${fmt(record.sim_time_s, 1)} s simulated`;
  root.replaceChildren(
    el("header", {}, el("h1", {}, `${sessionId} / ${taskId}`), verdict,
      el("a", { href: pageUrl(`/runs/${view.run}`) }, "← all tasks"), navLinks()),
    ...[el("p", { class: "muted" }, facts),
    el("p", { class: "task-text", id: "task-text" }, task.text || "(task text not recorded)"),
    record.error ? el("p", { class: "bad" }, record.error) : null,
    view.note ? el("p", { class: "note", id: "replay-note" }, view.note) : null].filter(Boolean));
  const body = el("div", { class: "task-body" });
  const side = el("aside", { class: "side" }, el("h3", {}, "Checks"), checkTree(record, task.checks));
  const main = el("div", { class: "task-main" });
  body.append(main, side);
  root.append(body);
  if (replay) {
    const world = buildWorld(view.world || {});
    const holder = { player: null };
    const overlays = [];
    const overlay = coverageOverlay(holder, record, world);
    const player = new ReplayPlayer(main, { world, replay, overlays });
    holder.player = player;
    if (overlay) player.map.overlays.push((ctx, map, layer) => overlay(ctx, map, layer));
    Object.defineProperty(holder, "paths", { get: () => player.paths });
    Object.defineProperty(holder, "t", { get: () => player.t });
    player.seek(player.t1);
    side.append(el("h3", {}, "Tool calls"), callList(player));
    const transcript = transcriptPanel(player, replay);
    if (transcript) main.append(transcript);
    window.consoleView = { map: player.map, get view3d() { return player.view3d; }, player, record };
  } else {
    window.consoleView = { record };
  }
}

function callList(player) {
  if (!player.calls.length) return el("p", { class: "muted" }, "no tool calls recorded");
  return el("ol", { class: "calls", id: "call-list" }, player.calls.map((c) => el("li", {
    class: `status-${c.status}`, onclick: () => player.seek(c.t0_s) }, callText(c, player.t0))));
}

export async function showTruth(root) {
  const view = await getJson("/api/truth");
  root.replaceChildren(...[el("header", {}, el("h1", {}, `Replay: ${view.name}`)),
    view.note ? el("p", { class: "note", id: "replay-note" }, view.note) : null].filter(Boolean));
  const main = el("div", { class: "task-main" });
  root.append(main);
  const player = new ReplayPlayer(main, { world: buildWorld(view.world || {}), replay: view.replay });
  window.consoleView = { map: player.map, get view3d() { return player.view3d; }, player };
}
