// Talking to the server: JSON in, JSON out, and the server's own message on errors; query strings
// and Server-Sent Event streams. Every page reaches the server through these functions.

export class ApiError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

async function unwrap(response) {
  if (response.ok) return response.json();
  let message = `${response.status} ${response.statusText}`;
  try {
    const body = await response.json();
    if (typeof body.detail === "string") message = body.detail;
    else if (Array.isArray(body.detail)) message = body.detail.map((d) => d.msg).join("; "); // FastAPI's 422
  } catch (_) { /* not JSON */ }
  throw new ApiError(response.status, message);
}

// `path` with `params` as its query string (undefined and null values left out).
export function withQuery(path, params) {
  if (!params) return path;
  const q = new URLSearchParams(Object.entries(params).filter(([, v]) => v !== undefined && v !== null)).toString();
  return q ? `${path}?${q}` : path;
}

// A file the server sends (e.g. an example recording), as a File named `name`.
export async function download(path, name) {
  const response = await fetch(path);
  if (!response.ok) await unwrap(response);
  const blob = await response.blob();
  return new File([blob], name, { type: blob.type });
}

export async function get(path, params) {
  return unwrap(await fetch(withQuery(path, params)));
}

export async function post(path, body) {
  return unwrap(await fetch(path, {
    method: "POST",
    headers: { "Content-Type": "application/json" },
    body: body === undefined ? undefined : JSON.stringify(body),
  }));
}

export async function put(path, body) {
  return unwrap(await fetch(path, {
    method: "PUT",
    headers: { "Content-Type": "application/json" },
    body: JSON.stringify(body),
  }));
}

export async function upload(path, field, file, params) {
  const form = new FormData();
  form.append(field, file, file.name);
  return unwrap(await fetch(withQuery(path, params), { method: "POST", body: form }));
}

// Server-Sent Events of `path`: `onEvent(JSON data)` for each event of the given types, and
// `onClosed(source)` once the server has closed the stream. Returns the EventSource (close() it to stop).
export function subscribe(path, types, onEvent, onClosed) {
  const source = new EventSource(path);
  for (const type of types) source.addEventListener(type, (ev) => onEvent(JSON.parse(ev.data)));
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) onClosed(source); };
  return source;
}
