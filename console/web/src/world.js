// The world as views draw it, from the session-file entity layout (drones, targets, obstacles
// with {x, y, z} positions in local east/north metres).

const CIRCLE_KINDS = new Set(["circle", "point", "fixed", "moving", "waypoint"]);

function xy(p) {
  return [Number(p?.x ?? 0), Number(p?.y ?? 0)];
}

export function shapeOf(entity, kind) {
  if (kind === "polygon") {
    return { type: "polygon", points: (entity.vertices || []).map(xy) };
  }
  const [x, y] = xy(entity.position);
  if (kind === "ellipse") {
    return { type: "ellipse", x, y, rx: Number(entity.width || 1), ry: Number(entity.length || 1) };
  }
  const fallback = CIRCLE_KINDS.has(kind) ? 1 : 1;
  return { type: "ellipse", x, y, rx: Number(entity.radius ?? fallback), ry: Number(entity.radius ?? fallback) };
}

export function shapeOutline(shape, segments = 48) {
  if (shape.type === "polygon") return shape.points;
  const out = [];
  for (let k = 0; k < segments; k++) {
    const a = (2 * Math.PI * k) / segments;
    out.push([shape.x + shape.rx * Math.cos(a), shape.y + shape.ry * Math.sin(a)]);
  }
  return out;
}

export function buildWorld(raw) {
  raw = raw || {};
  const obstacles = (raw.obstacles || []).map((o) => {
    const height = Number(o.height ?? 10);
    return { id: o.id, name: o.name || o.id, kind: o.type, height, allAltitudes: height === 0,
             shape: shapeOf(o, o.type) };
  });
  const targets = (raw.targets || []).map((t) => ({
    id: t.id, name: t.name || t.id, kind: t.type, area: t.type === "circle" || t.type === "polygon",
    station: t.type === "waypoint", shape: shapeOf(t, t.type), radius: Number(t.radius ?? 1),
  }));
  const drones = (raw.drones || []).map((d) => {
    const [x, y] = xy(d.position);
    return { id: d.id, name: d.name || d.id, x, y, z: Number(d.position?.z ?? 0),
             perceived: Number(d.perceived_radius ?? 50), taskRadius: Number(d.task_radius ?? 20) };
  });
  return { name: raw.name || raw.id || "", obstacles, targets, drones, bounds: bounds(raw, obstacles, targets, drones) };
}

function bounds(raw, obstacles, targets, drones) {
  let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
  const add = (x, y) => { x0 = Math.min(x0, x); y0 = Math.min(y0, y); x1 = Math.max(x1, x); y1 = Math.max(y1, y); };
  if (Array.isArray(raw.map_size_m)) { add(0, 0); add(raw.map_size_m[0], raw.map_size_m[1]); }
  for (const item of [...obstacles, ...targets]) for (const [x, y] of shapeOutline(item.shape, 8)) add(x, y);
  for (const d of drones) add(d.x, d.y);
  if (!Number.isFinite(x0)) { add(-50, -50); add(50, 50); }
  const pad = Math.max(10, 0.05 * Math.max(x1 - x0, y1 - y0));
  return [x0 - pad, y0 - pad, x1 + pad, y1 + pad];
}
