// The console page: picks its view from the path (after the base it is mounted at).

import { config, getJson, pageUrl } from "./api.js";
import { showEditor } from "./editor.js";
import { showCompare, showRuns, showTask, showTruth } from "./inspector.js";
import { showLeaderboard } from "./leaderboard.js";
import { showLive } from "./live.js";
import { el } from "./panel.js";

const HOME_POLL_MS = 2000;  // the home page asks for new live swarms and runs this often

function homeLists(info) {
  return [
    el("h2", {}, "Live"), info.live.length
      ? el("ul", { id: "live-list" }, info.live.map((l) => el("li", {}, el("a", { href: pageUrl(`/live/${encodeURIComponent(l.id)}`) }, `${l.name} (${l.drones} drones)`))))
      : el("p", { class: "muted", id: "live-list" }, "no live swarm here (yet: this page shows new ones as they start)"),
    el("h2", {}, "Recorded"),
    el("ul", { id: "run-list" }, info.runs.map((r) => el("li", {}, el("a", { href: pageUrl(`/runs/${r.id}`) }, `${r.id}: ${r.passed}/${r.tasks} tasks passed`))),
      info.truth ? el("li", {}, el("a", { href: pageUrl("/replay") }, `replay ${info.truth}`)) : null),
  ];
}

async function showHome(root) {
  // Sessions that start after the page was opened (a benchmark run's next session, a session
  // an operator loads) appear without a reload: the page asks again every HOME_POLL_MS.
  let seen = JSON.stringify(await getJson("/api/info"));
  const lists = el("div", { id: "home-lists" }, homeLists(JSON.parse(seen)));
  const note = el("p", { id: "home-note", class: "muted" }, "");
  root.replaceChildren(el("header", {}, el("h1", {}, "mavswarm console")), lists, note,
    el("h2", {}, "Edit"), el("a", { href: pageUrl("/editor") }, "scenario editor"));
  window.consoleView = { polls: 0 };
  setInterval(async () => {
    try {
      const text = JSON.stringify(await getJson("/api/info"));
      window.consoleView.polls += 1;
      note.textContent = "";
      if (text !== seen) { seen = text; lists.replaceChildren(...homeLists(JSON.parse(text))); }
    } catch (error) {
      note.textContent = `cannot reach the console server (${error.message}); trying again`;
    }
  }, HOME_POLL_MS);
}

async function route() {
  const root = document.getElementById("app");
  const path = location.pathname.slice(config.base.length) || "/";
  const parts = path.split("/").filter(Boolean).map(decodeURIComponent);
  const params = new URLSearchParams(location.search);
  try {
    if (parts[0] === "live" && parts[1]) await showLive(root, parts[1]);
    else if (parts[0] === "runs") await showRuns(root, parts[1]);
    else if (parts[0] === "inspect" && parts.length >= 3) await showTask(root, parts[1], parts[2], params);
    else if (parts[0] === "compare") await showCompare(root, params);
    else if (parts[0] === "leaderboard") await showLeaderboard(root);
    else if (parts[0] === "replay") await showTruth(root);
    else if (parts[0] === "editor") await showEditor(root);
    else await showHome(root);
  } catch (error) {
    root.replaceChildren(el("p", { class: "bad", id: "error" }, `${error.status ? `${error.status}: ` : ""}${error.message}`));
  }
  document.body.dataset.ready = "1";
}

route();
