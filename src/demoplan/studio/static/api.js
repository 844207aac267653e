// The studio's calls to its server (docs/studio-api.md). Every error becomes an
// ApiError carrying the server's one-line `detail`.

export class ApiError extends Error {
  constructor(status, detail) {
    super(detail);
    this.status = status;
  }
}

let pending = 0;

// body[data-pending] counts requests in flight (browser tests wait for "0").
function track(change) {
  pending += change;
  document.body.dataset.pending = String(pending);
}

function detailOf(data, response) {
  if (data && typeof data.detail === "string") return data.detail;
  if (data && Array.isArray(data.detail)) {
    return data.detail
      .map((d) => `${(d.loc || []).join(".")}: ${d.msg}`)
      .join("; ");
  }
  return `${response.status} ${response.statusText}`;
}

export async function api(method, path, body) {
  track(1);
  try {
    const init = { method, headers: {} };
    if (body !== undefined) {
      init.headers["Content-Type"] = "application/json";
      init.body = JSON.stringify(body);
    }
    let response;
    try {
      response = await fetch(path, init);
    } catch (error) {
      throw new ApiError(0, `the studio server does not answer (${error.message})`);
    }
    const text = await response.text();
    let data = null;
    try {
      data = text ? JSON.parse(text) : null;
    } catch {
      data = null;
    }
    if (!response.ok) throw new ApiError(response.status, detailOf(data, response));
    return data;
  } finally {
    track(-1);
  }
}

export const get = (path) => api("GET", path);
export const post = (path, body) => api("POST", path, body);
export const del = (path) => api("DELETE", path);
