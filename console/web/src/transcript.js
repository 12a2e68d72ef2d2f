// An LLM agent's transcript on its task's timeline (the run inspector): every message in order
// with its simulated time, the tool calls it made with their arguments in full, the tokens of
// each model turn. A click on a message moves the replay to its time; the message at the
// replay's time is highlighted as the replay plays, and each model turn is marked on the
// timeline's lanes.

import { el } from "./panel.js";

const TURN_COLOR = "#6c3483";

function pretty(text) {
  try { return JSON.stringify(JSON.parse(text), null, 1); } catch { return text; }
}

function tokensText(t) {
  return t ? `${t.prompt} + ${t.completion} tokens` : null;
}

function entryNode(e, k, t0, onPick) {
  const head = el("div", { class: "entry-head" },
    el("span", { class: "entry-t" }, `${(e.t_s - t0).toFixed(1)} s`),
    el("b", { class: "entry-role" }, e.role),
    e.agent ? el("span", { class: "entry-agent" }, `agent ${e.agent}`) : null,
    e.tool_call_id ? el("span", { class: "muted" }, `answers ${e.tool_call_id}`) : null,
    e.tokens ? el("span", { class: "entry-tokens" }, tokensText(e.tokens)) : null);
  const content = e.content ? el("div", { class: "entry-content" }, e.role === "tool" ? pretty(e.content) : e.content) : null;
  const calls = (e.tool_calls || []).length
    ? el("ul", { class: "entry-calls" }, e.tool_calls.map((c) => el("li", {},
      el("code", { class: "call-name" }, c.name || "(unnamed)"), el("span", { class: "muted" }, ` ${c.id}`),
      el("pre", { class: "call-args" }, pretty(c.arguments)))))
    : null;
  return el("li", { class: `entry role-${e.role}`, "data-index": k, onclick: () => onPick(k) }, head, content, calls);
}

// The transcript panel for `player` (a ReplayPlayer), or null when the agent recorded none.
export function transcriptPanel(player, replay) {
  const entries = replay.transcript || [];
  const dropped = replay.transcript_dropped || 0;
  if (!entries.length && !dropped) return null;
  player.transcript = entries;
  let picked = null;
  const pick = (k) => { picked = k; player.seek(entries[k].t_s); };
  const nodes = entries.map((e, k) => entryNode(e, k, player.t0, pick));
  const turns = entries.filter((e) => e.tokens);
  const prompt = turns.reduce((s, e) => s + e.tokens.prompt, 0), completion = turns.reduce((s, e) => s + e.tokens.completion, 0);
  const list = el("ol", { class: "transcript-list" }, nodes);
  const panel = el("section", { id: "transcript", class: "transcript" },
    el("h3", {}, "Transcript"),
    el("p", { class: "muted", id: "transcript-summary" },
      `${entries.length} messages · ${turns.length} model turns · ${prompt} prompt + ${completion} completion tokens · click a message to move the replay to its time`),
    dropped ? el("p", { class: "note" }, `${dropped} later messages were not kept (a task's transcript is bounded)`) : null,
    list);
  let current = -1;
  const mark = () => {
    let k = picked !== null && Math.abs(entries[picked].t_s - player.t) < 1e-6 ? picked : -1;
    if (k < 0) {
      picked = null;
      for (let j = 0; j < entries.length && entries[j].t_s <= player.t + 1e-6; j++) k = j;
    }
    if (k === current) return;
    if (current >= 0) nodes[current].classList.remove("current");
    current = k;
    if (k >= 0) nodes[k].classList.add("current");
  };
  // The player draws itself on every seek and step of play: follow it, and mark each model
  // turn on the lanes (a tick under the time axis).
  const render = player.render.bind(player), lanes = player._drawLanes.bind(player);
  player.render = () => { render(); mark(); };
  player._drawLanes = () => {
    lanes();
    const canvas = player.lanes, ctx = canvas.getContext("2d"), w = canvas.clientWidth || 800;
    ctx.fillStyle = TURN_COLOR;
    for (const e of turns) {
      const x = player._x(e.t_s, w);
      ctx.beginPath(); ctx.moveTo(x - 4, 0); ctx.lineTo(x + 4, 0); ctx.lineTo(x, 6); ctx.fill();
    }
  };
  player.render();
  return panel;
}
