// Small DOM helpers and the per-drone panel shared by the live view and the replay.

export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (key === "class") node.className = value;
    else if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else if (value !== undefined && value !== null) node.setAttribute(key, value);
  }
  for (const child of children.flat()) {
    if (child === null || child === undefined) continue;
    node.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return node;
}

export function fmt(value, digits = 1, unit = "") {
  if (value === null || value === undefined || Number.isNaN(value)) return "–";
  return `${Number(value).toFixed(digits)}${unit}`;
}

export function dronePanel(drone, activity) {
  if (!drone) return el("p", { class: "muted" }, "Click a drone on the map to select it.");
  const act = activity || {};
  const executing = act.executing ? `${act.executing.name}(${argsText(act.executing.args)})` : "none";
  const last = act.last ? `${act.last.name}: ${act.last.status} — ${act.last.message}` : "none yet";
  const rows = [
    ["mode", drone.mode ?? "–"], ["armed", drone.armed === undefined ? "–" : drone.armed ? "yes" : "no"],
    ["altitude", fmt(drone.z, 1, " m")], ["speed", fmt(drone.spd, 1, " m/s")],
    ["battery", fmt(drone.bat, 1, " %")], ["position", `${fmt(drone.x, 1)}, ${fmt(drone.y, 1)} m`],
    ["heading", fmt(drone.yaw, 0, "°")], ["executing", executing], ["last outcome", last],
  ];
  return el("table", { class: "kv", id: "drone-panel" },
    el("caption", {}, drone.id),
    rows.map(([k, v]) => el("tr", { "data-field": k }, el("th", {}, k), el("td", {}, v))));
}

export function argsText(args) {
  if (!args) return "";
  return Object.entries(args).filter(([k]) => k !== "drone_id")
    .map(([k, v]) => `${k}=${typeof v === "number" ? +v.toFixed(2) : JSON.stringify(v)}`).join(", ");
}

export function toggleBar(map, onChange = () => {}) {
  const box = (name, label) => el("label", {},
    el("input", { type: "checkbox", id: `toggle-${name}`, ...(map.toggles[name] ? { checked: "" } : {}),
      onchange: (e) => { map.toggles[name] = e.target.checked; map.redraw(); onChange(); } }), ` ${label}`);
  return el("div", { class: "toggles" }, box("perception", "perception radius"), box("task", "task radius"),
    box("labels", "labels"), el("button", { onclick: () => map.fit() }, "fit map"));
}

export function legend() {
  const item = (cls, text) => el("span", { class: "legend-item" }, el("i", { class: cls }), text);
  return el("div", { class: "legend" }, item("lg-drone", "drone"), item("lg-building", "building (height)"),
    item("lg-wall", "obstacle, all altitudes"), item("lg-mast", "point obstacle"), item("lg-area", "area target"), item("lg-point", "point target"),
    item("lg-station", "charging station"));
}
