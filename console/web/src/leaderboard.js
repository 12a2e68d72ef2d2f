// Every (run, agent) that `mavswarm replay` serves, ranked: task pass rate, average and global
// check with their 95 % intervals (bootstrap over whole sessions), tokens, cost and time. Click
// a column to sort by it (again to reverse); rows on another suite than the first are marked.

import { getJson, pageUrl } from "./api.js";
import { navLinks } from "./nav.js";
import { el } from "./panel.js";

const pct = (v) => `${(v * 100).toFixed(1)} %`;

const COLUMNS = [
  { name: "run", get: (r) => r.id, text: (r) => el("a", { href: pageUrl(`/runs/${r.console_run}`) }, r.id) },
  { name: "agent", get: (r) => r.agent },
  { name: "tasks", get: (r) => r.tasks },
  { name: "Task Pass", get: (r) => r.task_pass_rate.value, interval: (r) => r.task_pass_rate },
  { name: "Avg. Check", get: (r) => r.average_check.value, interval: (r) => r.average_check },
  { name: "Global Check", get: (r) => r.global_check.value, interval: (r) => r.global_check },
  { name: "tokens", get: (r) => r.tokens.prompt + r.tokens.completion },
  { name: "cost (USD)", get: (r) => r.tokens.cost_usd, text: (r) => r.tokens.cost_usd.toFixed(4) },
  { name: "mean sim s", get: (r) => r.time.mean_sim_time_s ?? -1, text: (r) => (r.time.mean_sim_time_s ?? 0).toFixed(1) },
  { name: "suite", get: (r) => r.fingerprint },
];

function intervalCell(i) {
  const bar = el("div", { class: "ci-bar" }, el("span", { class: "ci-range", style: `left:${i.low * 100}%;width:${Math.max((i.high - i.low) * 100, 0.5)}%` }),
    el("span", { class: "ci-dot", style: `left:${i.value * 100}%` }));
  return el("td", { "data-value": i.value, title: `95 % interval ${pct(i.low)} to ${pct(i.high)}` },
    `${pct(i.value)} [${(i.low * 100).toFixed(1)}, ${(i.high * 100).toFixed(1)}]`, bar);
}

export async function showLeaderboard(root) {
  const rows = (await getJson("/api/leaderboard")).rows;
  if (!rows.length) { root.replaceChildren(el("p", {}, "No results folders were opened.")); return; }
  const suite = rows[0].fingerprint;
  let sort = { column: 3, descending: true };
  const table = el("table", { class: "tasks", id: "leaderboard" });
  function render() {
    const col = COLUMNS[sort.column];
    const ordered = [...rows].sort((x, y) => {
      const a = col.get(x), b = col.get(y);
      const order = typeof a === "number" ? a - b : String(a).localeCompare(String(b));
      return sort.descending ? -order : order;
    });
    const best = rows.reduce((x, y) => (y.task_pass_rate.value > x.task_pass_rate.value ? y : x));
    table.replaceChildren(
      el("tr", {}, el("th", {}, "#"), COLUMNS.map((c, k) => el("th", { class: `sortable${k === sort.column ? (sort.descending ? " desc" : " asc") : ""}`,
        "data-column": c.name, onclick: () => { sort = { column: k, descending: k === sort.column ? !sort.descending : typeof c.get(rows[0]) !== "string" }; render(); } }, c.name)),
      el("th", {}, "")),
      ...ordered.map((r, n) => el("tr", { "data-run": r.id, class: r.fingerprint !== suite ? "other-suite" : "" }, el("td", {}, n + 1),
        COLUMNS.map((c) => c.interval ? intervalCell(c.interval(r)) : el("td", {}, c.text ? c.text(r) : c.get(r))),
        el("td", {}, r.id === best.id ? "" : el("a", { href: pageUrl("/compare", { a: best.id, b: r.id }) }, `compare with ${best.id}`)))));
  }
  root.replaceChildren(el("header", {}, el("h1", {}, "Leaderboard"), navLinks("leaderboard")),
  el("p", { class: "muted" }, `${rows.length} runs. Intervals: 95 % bootstrap over whole sessions (tasks of a session share its world). ` +
    "Rows on another suite than the first are shaded: their rates are over other tasks."),
  table);
  render();
}
