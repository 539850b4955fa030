// The REST client: the operator token and one fetch wrapper that turns every failure into an
// ApiError with a sentence an operator can act on.

const TOKEN_KEY = "nemesys.token";

/**
 * This page's own 3D view: a random id made when the page loads. The page opens viser's client
 * with it (the websocket URL ws://host:port/view/<id>, see withView) and sends it as
 * X-Nemesys-View on every API call, so its previews and replays are drawn in its view only.
 * crypto.getRandomValues, not randomUUID: the latter exists only in secure contexts (a console
 * opened over the LAN by plain http is not one).
 */
export const VIEW_ID = Array.from(crypto.getRandomValues(new Uint8Array(16)), (b) => b.toString(16).padStart(2, "0")).join("");

/** The session's viewer_url with this page's view in its websocket URL (.../view/<VIEW_ID>). */
export function withView(viewerUrl) {
  return viewerUrl.replace(/([?&]websocket=)([^&#]*)/, (_, key, value) => {
    let ws = decodeURIComponent(value);
    try {
      const u = new URL(ws);
      u.pathname = `/view/${VIEW_ID}`;
      ws = u.href;
    } catch {
      ws = `${ws.replace(/\/+$/, "")}/view/${VIEW_ID}`;
    }
    return key + ws;
  });
}
let memoryToken = ""; // used when sessionStorage is unavailable

export function getToken() {
  try {
    return sessionStorage.getItem(TOKEN_KEY) || "";
  } catch {
    return "";
  }
}

export function setToken(token) {
  try {
    if (token) sessionStorage.setItem(TOKEN_KEY, token);
    else sessionStorage.removeItem(TOKEN_KEY);
  } catch {
    // storage disabled: the token lives only as long as the page
  }
  memoryToken = token;
}

function currentToken() {
  return getToken() || memoryToken;
}

/** Take ?token= from the address, keep it, and remove it from the visible URL. */
export function adoptUrlToken() {
  const url = new URL(window.location.href);
  const token = url.searchParams.get("token");
  if (token === null) return;
  setToken(token.trim());
  url.searchParams.delete("token");
  window.history.replaceState(null, "", url.pathname + url.search + url.hash);
}

export class ApiError extends Error {
  constructor(status, detail, retryAfter = null) {
    super(describe(status, detail, retryAfter));
    this.status = status;
    this.detail = detail;
    this.retryAfter = retryAfter;
  }

  /** [{param, msg}] from FastAPI's 422 list, a {field, message} object or a plain string. */
  get items() {
    return detailItems(this.detail);
  }
}

export function detailItems(detail) {
  if (Array.isArray(detail)) {
    return detail.map((d) => {
      if (d && typeof d === "object") {
        const loc = Array.isArray(d.loc) ? d.loc : [];
        return { param: loc.length ? String(loc[loc.length - 1]) : "", msg: d.msg || d.message || JSON.stringify(d) };
      }
      return { param: "", msg: String(d) };
    });
  }
  if (detail && typeof detail === "object") {
    if (Array.isArray(detail.violations)) {
      return detail.violations.map((v) => ({ param: v.param || "", msg: v.message || JSON.stringify(v) }));
    }
    return [{ param: detail.field || detail.param || "", msg: detail.message || detail.msg || detail.reason || JSON.stringify(detail) }];
  }
  return [{ param: "", msg: detail == null ? "" : String(detail) }];
}

function describe(status, detail, retryAfter) {
  const text = detailItems(detail)
    .map((i) => (i.param ? `${i.param}: ${i.msg}` : i.msg))
    .filter(Boolean)
    .join("; ");
  switch (status) {
    case 0:
      return `backend unreachable (${text || "network error"})`;
    case 401:
      return `401 not authorised: this needs the operator token (open the URL with ?token=...)${text ? ` (${text})` : ""}`;
    case 403:
      return `403 forbidden: the operator token was rejected${text ? ` (${text})` : ""}`;
    case 429:
      return `429 rate limited: try again${retryAfter ? ` in ${retryAfter} s` : " shortly"}${text ? ` (${text})` : ""}`;
    default:
      return `${status}: ${text || "request failed"}`;
  }
}

/**
 * Call the API. Sends the bearer token when there is one. Resolves to the parsed body (JSON or
 * text); rejects with ApiError (status 0 for network failures). AbortError passes through.
 */
export async function api(path, { method = "GET", body, signal } = {}) {
  const headers = { Accept: "application/json", "X-Nemesys-View": VIEW_ID };
  if (body !== undefined) headers["Content-Type"] = "application/json";
  const token = currentToken();
  if (token) headers.Authorization = `Bearer ${token}`;
  let response;
  try {
    response = await fetch(path, {
      method,
      headers,
      body: body === undefined ? undefined : JSON.stringify(body),
      signal,
    });
  } catch (err) {
    if (err && err.name === "AbortError") throw err;
    throw new ApiError(0, String((err && err.message) || err));
  }
  const type = response.headers.get("content-type") || "";
  let data = null;
  try {
    data = type.includes("json") ? await response.json() : await response.text();
  } catch {
    data = null;
  }
  if (!response.ok) {
    const detail = data && typeof data === "object" && "detail" in data ? data.detail : data || response.statusText;
    if ((response.status === 401 || response.status === 403) && !path.startsWith("/api/session")) {
      window.dispatchEvent(new CustomEvent("nemesys:auth-error", { detail: response.status }));
    }
    throw new ApiError(response.status, detail, response.headers.get("Retry-After"));
  }
  return data;
}

export function hasToken() {
  return Boolean(currentToken());
}

export function tokenValue() {
  return currentToken();
}
