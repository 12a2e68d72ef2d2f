// The check tree of a task with each leaf's measured value, threshold and verdict, so a failure
// reads at a glance ("coverage of t6: 0.65 < 0.95"); and the uncovered part of a failed
// coverage check shaded on the map.

import { el } from "./panel.js";
import { shapeOutline } from "./world.js";

const THRESHOLD = /^(min_|max_|expected_)|threshold|tolerance|percentage|^ratio$/;

function show(value) {
  if (typeof value === "number") return Number.isInteger(value) ? String(value) : value.toFixed(3).replace(/0+$/, "").replace(/\.$/, "");
  if (value === null || value === undefined) return "–";
  return JSON.stringify(value);
}

export function explainLeaf(leaf) {
  const p = leaf.parameters || {};
  const subject = ["target_id", "drone_id", "area_id", "target_ids", "drone_ids"].filter((k) => p[k] !== undefined)
    .map((k) => show(p[k]).replaceAll('"', "")).join(", ");
  const name = leaf.endpoint.replaceAll("_", " ");
  const key = Object.keys(p).find((k) => THRESHOLD.test(k));
  if (leaf.error) return `${name}${subject ? ` of ${subject}` : ""}: could not be evaluated — ${leaf.error}`;
  const value = leaf.value;
  if (key !== undefined && typeof value === "number") {
    const limit = p[key];
    const atMost = key.startsWith("max_") || key.includes("tolerance");
    const holds = atMost ? value <= limit : value >= limit;
    const op = atMost ? (holds ? "≤" : ">") : (holds ? "≥" : "<");
    return `${name}${subject ? ` of ${subject}` : ""}: ${show(value)} ${op} ${show(limit)} (${key})`;
  }
  const expect = leaf.expect === false ? " (expected false)" : "";
  return `${name}${subject ? ` of ${subject}` : ""}: measured ${show(value)}, result ${show(leaf.result)}${expect}`;
}

function nodeView(node, path, leaves) {
  if (node && node.endpoint) {
    const leaf = leaves.get(path) || { endpoint: node.endpoint, parameters: node.parameters, value: null, passed: false, error: "not evaluated" };
    return el("li", { class: `leaf ${leaf.passed ? "pass" : "fail"}`, "data-endpoint": leaf.endpoint },
      el("span", { class: "verdict" }, leaf.passed ? "✔" : "✘"), " ", explainLeaf(leaf),
      el("div", { class: "params muted" }, `${leaf.endpoint} ${JSON.stringify(leaf.parameters)}`));
  }
  const children = (node?.checks || []).map((child, k) => nodeView(child, `${path}[${k}]`, leaves));
  return el("li", { class: "group" }, el("b", {}, (node?.logic || "and").toUpperCase()), el("ul", {}, children));
}

export function checkTree(record, tree) {
  const leaves = new Map((record.checks || []).map((leaf) => [leaf.path, leaf]));
  if (!tree) {
    return el("ul", { class: "checks", id: "check-tree" }, (record.checks || []).map((leaf) => nodeView(
      { endpoint: leaf.endpoint, parameters: leaf.parameters }, leaf.path, leaves)));
  }
  return el("ul", { class: "checks", id: "check-tree" }, nodeView(tree, "checks", leaves));
}

export function coverageOverlay(player, record, world) {
  const failed = (record.checks || []).filter((c) => !c.passed && /coverage|searched/.test(c.endpoint) && c.parameters?.target_id);
  const targets = failed.map((c) => world.targets.find((t) => t.id === c.parameters.target_id)).filter(Boolean);
  if (!targets.length) return null;
  const radius = new Map(world.drones.map((d) => [d.id, d.taskRadius]));
  const off = document.createElement("canvas");
  return (ctx, map, layer) => {
    if (layer !== "below") return;
    off.width = ctx.canvas.width; off.height = ctx.canvas.height;
    const o = off.getContext("2d");
    o.setTransform(map.dpr, 0, 0, map.dpr, 0, 0);
    o.fillStyle = "rgba(217, 4, 41, 0.45)";
    for (const t of targets) {
      o.beginPath();
      shapeOutline(t.shape, 96).forEach(([x, y], k) => { const [sx, sy] = map.toScreen(x, y); k ? o.lineTo(sx, sy) : o.moveTo(sx, sy); });
      o.closePath(); o.fill();
    }
    o.globalCompositeOperation = "destination-out";
    o.lineCap = "round"; o.lineJoin = "round"; o.strokeStyle = "#000";
    for (const [id, p] of player.paths) {
      o.lineWidth = 2 * (radius.get(id) ?? 20) * map.view.scale;
      o.beginPath();
      let open = false;
      for (let k = 0; k < p.t.length && p.t[k] <= player.t; k++) {
        const [sx, sy] = map.toScreen(p.x[k], p.y[k]);
        if (p.z[k] > 0.5) { if (open) o.lineTo(sx, sy); else { o.moveTo(sx, sy); open = true; } } else open = false;
      }
      o.stroke();
    }
    o.globalCompositeOperation = "source-over";
    ctx.save(); ctx.setTransform(1, 0, 0, 1, 0, 0); ctx.drawImage(off, 0, 0); ctx.restore();
  };
}
