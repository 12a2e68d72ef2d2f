// The console page: picks its view from the path (after the base it is mounted at).

import { config, getJson, pageUrl } from "./api.js";
import { showEditor } from "./editor.js";
import { showCompare, showRuns, showTask, showTruth } from "./inspector.js";
import { showLeaderboard } from "./leaderboard.js";
import { showLive } from "./live.js";
import { el } from "./panel.js";

async function showHome(root) {
  const info = await getJson("/api/info");
  root.replaceChildren(el("header", {}, el("h1", {}, "mavswarm console")),
    el("h2", {}, "Live"), info.live.length
      ? el("ul", {}, info.live.map((l) => el("li", {}, el("a", { href: pageUrl(`/live/${encodeURIComponent(l.id)}`) }, `${l.name} (${l.drones} drones)`))))
      : el("p", { class: "muted" }, "no live swarm here"),
    el("h2", {}, "Recorded"),
    el("ul", {}, info.runs.map((r) => el("li", {}, el("a", { href: pageUrl(`/runs/${r.id}`) }, `${r.id}: ${r.passed}/${r.tasks} tasks passed`))),
      info.truth ? el("li", {}, el("a", { href: pageUrl("/replay") }, `replay ${info.truth}`)) : null),
    el("h2", {}, "Edit"), el("a", { href: pageUrl("/editor") }, "scenario editor"));
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
