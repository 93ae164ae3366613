// Talking to the server: JSON in, JSON out, and the server's own message on errors.

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
    else if (Array.isArray(body.detail)) message = body.detail.map((d) => d.msg).join("; ");
  } catch (_) { /* not JSON */ }
  throw new ApiError(response.status, message);
}

export async function get(path) {
  return unwrap(await fetch(path));
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

export async function upload(path, field, file) {
  const form = new FormData();
  form.append(field, file, file.name);
  return unwrap(await fetch(path, { method: "POST", body: form }));
}
