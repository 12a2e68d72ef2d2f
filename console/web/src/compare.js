// Two runs compared (/compare?a=RUN&b=RUN, ids as /api/leaderboard gives them): the headline
// metrics with their differences and paired-bootstrap intervals, paired changes by family and
// level (McNemar p), and the tasks side by side, optionally only those whose verdict differs.
// With &session=S&task=T&trial=K: that task's two replays side by side, on one timeline (time
// since each window opened), scrubbing or playing either moves both.

import { getJson, pageUrl } from "./api.js";
import { checkTree } from "./checks.js";
import { navLinks } from "./nav.js";
import { el } from "./panel.js";
import { ReplayPlayer } from "./replay.js";
import { buildWorld } from "./world.js";

const pct = (v) => (v === null || v === undefined ? "–" : `${(v * 100).toFixed(1)} %`);
const span = (i) => `${pct(i.value)} [${(i.low * 100).toFixed(1)}, ${(i.high * 100).toFixed(1)}]`;
const pp = (v) => `${v >= 0 ? "+" : ""}${(v * 100).toFixed(1)} pp`;
const signed = (i) => `${pp(i.value)} [${pp(i.low)}, ${pp(i.high)}]`;
const pText = (p) => (p >= 0.9995 ? "1" : p >= 0.001 ? p.toFixed(3) : p.toExponential(1));
const trend = (v) => (v > 0 ? "up" : v < 0 ? "down" : "");

function metricTable(report) {
  const [a, b] = report.runs, pair = report.pairs[0];
  const rows = [["Task Pass", "task_pass_rate", "task_pass_rate_diff"], ["Avg. Check", "average_check", "average_check_diff"],
    ["Global Check", "global_check", "global_check_diff"]];
  return el("table", { class: "tasks", id: "compare-metrics" },
    el("tr", {}, ["metric", `A: ${a.id}`, `B: ${b.id}`, "B − A (paired)"].map((h) => el("th", {}, h))),
    rows.map(([label, key, diff]) => el("tr", {}, el("td", {}, label), el("td", {}, span(a[key])), el("td", {}, span(b[key])),
      el("td", { class: trend(pair[diff].value) }, signed(pair[diff])))));
}

function groupTable(report, group) {
  const [a, b] = report.runs, pair = report.pairs[0];
  const labels = Object.keys(pair[`by_${group}`]);
  return el("table", { class: "tasks", id: `compare-${group}` },
    el("tr", {}, [group, "A", "B", "Δ pass rate", "fail→pass", "pass→fail", "McNemar p"].map((h) => el("th", {}, h))),
    labels.map((label) => {
      const t = pair[`by_${group}`][label], ra = a[`by_${group}`][label], rb = b[`by_${group}`][label];
      return el("tr", { class: t.fail_to_pass || t.pass_to_fail ? "differ" : "" }, el("td", {}, label),
        el("td", {}, ra ? `${pct(ra.pass_rate)} (${ra.passed}/${ra.tasks})` : "–"),
        el("td", {}, rb ? `${pct(rb.pass_rate)} (${rb.passed}/${rb.tasks})` : "–"),
        el("td", { class: trend(t.pass_rate_change) }, pp(t.pass_rate_change)),
        el("td", { class: "up" }, t.fail_to_pass), el("td", { class: "down" }, t.pass_to_fail),
        el("td", { class: t.mcnemar_p < 0.05 ? "sig" : "" }, pText(t.mcnemar_p)));
    }));
}

async function showPairedTask(root, params, a, b, side) {
  const session = params.get("session"), task = params.get("task"), trial = params.get("trial") || "0";
  const load = (id) => getJson(`/api/task/${encodeURIComponent(session)}/${encodeURIComponent(task)}?` +
    new URLSearchParams({ trial, run: side(id).console_run, agent: side(id).agent }));
  const views = await Promise.all([load(a), load(b)]);
  const back = new URLSearchParams({ a, b });
  root.replaceChildren(el("header", {}, el("h1", {}, `${session} / ${task} (trial ${trial})`),
    el("a", { href: pageUrl("/compare", Object.fromEntries(back)) }, "← compare")),
  el("p", { class: "task-text" }, views.find((v) => v.replay)?.replay.task?.text || "(task text not recorded)"));
  const columns = el("div", { class: "paired-replays" });
  root.append(columns);
  const players = [];
  views.forEach((view, k) => {
    const id = [a, b][k], record = view.record;
    const column = el("div", { class: "paired-side", id: `side-${"ab"[k]}` },
      el("h2", {}, `${"AB"[k]}: ${id} `, el("span", { class: record.passed ? "ok" : "bad" }, record.passed ? "PASS" : "FAIL"),
        ` ${record.checks_passed}/${record.checks_total} checks`),
      el("a", { href: pageUrl(`/inspect/${session}/${task}`, { trial, run: side(id).console_run, agent: side(id).agent }) }, "inspect"));
    columns.append(column);
    if (!view.replay) { column.append(el("p", { class: "note" }, view.note || "no replay")); return; }
    const player = new ReplayPlayer(column, { world: buildWorld(view.world || {}), replay: view.replay });
    column.append(el("h3", {}, "Checks"), checkTree(record, view.replay.task?.checks));
    players.push(player);
  });
  let following = false;
  for (const player of players) {
    const own = player.seek.bind(player);
    player.seek = (t) => {
      own(t);
      if (following) return;
      following = true;
      for (const other of players) if (other !== player) other.seek(other.t0 + (player.t - player.t0));
      following = false;
    };
  }
  players.forEach((p) => p.seek(p.t0));
  window.consoleView = { players, records: views.map((v) => v.record) };
}

export async function showCompare(root, params) {
  const board = (await getJson("/api/leaderboard")).rows;
  if (board.length < 2) { root.replaceChildren(el("p", {}, "Open two results folders (or a run with two agents) to compare.")); return; }
  const ids = board.map((r) => r.id);
  const a = ids.includes(params.get("a")) ? params.get("a") : ids[0];
  const b = ids.includes(params.get("b")) && params.get("b") !== a ? params.get("b") : ids.find((id) => id !== a);
  const side = (id) => board.find((r) => r.id === id);
  if (params.get("session") && params.get("task")) { await showPairedTask(root, params, a, b, side); return; }
  const [report, rowsA, rowsB] = await Promise.all([
    getJson(`/api/compare?a=${encodeURIComponent(a)}&b=${encodeURIComponent(b)}`),
    ...[a, b].map(async (id) => (await getJson(`/api/runs/${encodeURIComponent(side(id).console_run)}/tasks`)).rows
      .filter((r) => r.agent === side(id).agent))]);
  const key = (r) => `${r.session}/${r.task}/${r.trial}`;
  const byB = new Map(rowsB.map((r) => [key(r), r]));
  const differs = (r) => byB.has(key(r)) && !!byB.get(key(r)).passed !== !!r.passed;
  const chooser = (name, current) => el("select", { id: `compare-${name}`, onchange: (e) => { params.set(name, e.target.value); location.search = params.toString(); } },
    ids.map((id) => el("option", { value: id, ...(id === current ? { selected: "" } : {}) }, `${id} (${side(id).agent})`)));
  const link = (r, id) => pageUrl(`/inspect/${r.session}/${r.task}`, { trial: r.trial, run: side(id).console_run, agent: side(id).agent });
  const cell = (r, id) => r ? el("td", { class: r.passed ? "pass" : "fail" }, el("a", { href: link(r, id) }, r.passed ? "PASS" : "FAIL"),
    ` ${r.checks_passed}/${r.checks_total}`) : el("td", {}, "–");
  const only = el("input", { type: "checkbox", id: "differences-only", onchange: () => render() });
  const table = el("table", { class: "tasks", id: "compare-table" });
  const count = el("span", { id: "compare-count" });
  function render() {
    const shown = rowsA.filter((r) => !only.checked || differs(r));
    count.textContent = `${shown.length} of ${rowsA.length} tasks shown`;
    table.replaceChildren(el("tr", {}, ["session", "task", "trial", "A", "B", "replays"].map((h) => el("th", {}, h))),
      ...shown.map((r) => el("tr", { class: differs(r) ? "differ" : "" },
        el("td", {}, r.session), el("td", {}, r.task), el("td", {}, r.trial), cell(r, a), cell(byB.get(key(r)), b),
        el("td", {}, byB.has(key(r)) ? el("a", { class: "side-by-side", href: pageUrl("/compare", { a, b, session: r.session, task: r.task, trial: r.trial }) }, "side by side") : ""))));
  }
  const t = report.pairs[0].overall;
  root.replaceChildren(el("header", {}, el("h1", {}, "Compare"), navLinks("compare")),
  el("div", { class: "filters" }, "A ", chooser("a", a), " B ", chooser("b", b)),
  el("p", { id: "compare-summary" }, `A passes ${rowsA.filter((r) => r.passed).length}/${rowsA.length}, B passes ${rowsB.filter((r) => r.passed).length}/${rowsB.length}; ` +
    `${rowsA.filter(differs).length} tasks differ (${t.fail_to_pass} fail→pass, ${t.pass_to_fail} pass→fail, McNemar p = ${pText(t.mcnemar_p)})`),
  ...report.warnings.map((w) => el("p", { class: "note" }, `warning: ${w}`)),
  el("p", { class: "muted" }, `95 % intervals: bootstrap over whole sessions (${report.bootstrap.resamples} resamples), the same draws for both runs.`),
  metricTable(report), el("h2", {}, "By family"), groupTable(report, "family"), el("h2", {}, "By level"), groupTable(report, "level"),
  el("h2", {}, "Tasks"), el("div", { class: "filters" }, el("label", {}, only, " differences only"), count), table);
  render();
}
