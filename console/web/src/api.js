// Talking to the console's server: the base path it is mounted at, the operator key (from the
// page's ?key= or this tab's storage) sent with every request, and the live WebSocket.

export const config = window.CONSOLE || { base: "", open: false };

export function apiKey() {
  const fromUrl = new URLSearchParams(location.search).get("key");
  if (fromUrl) sessionStorage.setItem("mavswarm-key", fromUrl);
  return fromUrl || sessionStorage.getItem("mavswarm-key") || "";
}

export function url(path) {
  return `${config.base}${path}`;
}

export function pageUrl(path, params = {}) {
  const query = new URLSearchParams(params);
  const key = new URLSearchParams(location.search).get("key");
  if (key) query.set("key", key);
  const text = query.toString();
  return url(path) + (text ? `?${text}` : "");
}

export class ApiError extends Error {
  constructor(status, detail) {
    super(detail);
    this.status = status;
  }
}

async function answer(response) {
  const text = await response.text();
  let body = null;
  try { body = text ? JSON.parse(text) : null; } catch { body = { detail: text }; }
  if (!response.ok && response.status !== 422) {
    throw new ApiError(response.status, (body && (body.detail || body.error)) || response.statusText);
  }
  return { status: response.status, body };
}

export async function getJson(path) {
  return (await getAnswer(path)).body;
}

// {status, body} of a GET: 200 or 422 (a refusal to show); any other status throws ApiError.
export async function getAnswer(path) {
  const response = await fetch(url(path), { headers: { "X-API-Key": apiKey() } });
  return answer(response);
}

export async function postJson(path, data) {
  const response = await fetch(url(path), {
    method: "POST",
    headers: { "X-API-Key": apiKey(), "Content-Type": "application/json" },
    body: JSON.stringify(data),
  });
  return answer(response);
}

// {status, body} of a POST of raw text (an uploaded file's content, sent as it is).
export async function postText(path, text) {
  const response = await fetch(url(path), {
    method: "POST",
    headers: { "X-API-Key": apiKey(), "Content-Type": "application/json" },
    body: text,
  });
  return answer(response);
}

export function liveSocket(liveId) {
  const scheme = location.protocol === "https:" ? "wss" : "ws";
  const key = encodeURIComponent(apiKey());
  return new WebSocket(`${scheme}://${location.host}${url(`/api/live/${encodeURIComponent(liveId)}/ws`)}?key=${key}`);
}
