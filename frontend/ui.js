// DOM helpers, the message area, number formatting with units, and read-only gating.

export const $ = (id) => document.getElementById(id);

/** el("button", {class: "x", dataset: {testid: "y"}, onclick}, "text", child) */
export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === undefined || value === null || value === false) continue;
    if (key === "class") node.className = value;
    else if (key === "testid") node.dataset.testid = value;
    else if (key === "dataset") Object.assign(node.dataset, value);
    else if (key.startsWith("on") && typeof value === "function") node.addEventListener(key.slice(2), value);
    else if (key in node && typeof value !== "string") node[key] = value;
    else node.setAttribute(key, value === true ? "" : value);
  }
  for (const child of children.flat()) {
    if (child === null || child === undefined || child === false) continue;
    node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

// ---- messages ----

/** Show a dismissable message; kind is "info", "warn" or "error". Information fades after 8 s,
 * a warning after 10 s; an error stays until dismissed, or until its cause is fixed: `key` names
 * the cause (notifyError's prefix), a new message of the same key replaces the old one, and
 * resolved(key) removes it (the caller's same action succeeded). */
const MAX_TOASTS = 3;
const FADE_MS = { info: 8000, warn: 10000 };

export function notify(text, kind = "info", key = null) {
  const box = $("messages");
  if (!box) return;
  if (key) resolved(key);
  const item = el(
    "div",
    { class: `message message-${kind}`, testid: "message", role: kind === "error" ? "alert" : "status" },
    el("span", {}, text),
    el("button", { type: "button", class: "dismiss", testid: "message-dismiss", "aria-label": "dismiss message", onclick: () => item.remove() }, "×"),
  );
  if (key) item.dataset.key = key;
  box.prepend(item);
  // at most MAX_TOASTS stacked: the oldest that is not an error goes first
  while (box.children.length > MAX_TOASTS) {
    const oldestFirst = [...box.children].reverse();
    (oldestFirst.find((c) => !c.classList.contains("message-error")) || oldestFirst[0]).remove();
  }
  // information fades (the command's row keeps what it said); errors stay until dismissed
  if (kind in FADE_MS) setTimeout(() => item.remove(), FADE_MS[kind]);
}

/** An error message keyed by `prefix` (its cause): resolved(prefix) takes it away. */
export function notifyError(prefix, err) {
  if (err && err.name === "AbortError") return;
  notify(`${prefix}: ${(err && err.message) || err}`, "error", prefix);
}

/** The cause `key` is fixed (the same action succeeded): its message goes. */
export function resolved(key) {
  const box = $("messages");
  if (!box) return;
  for (const item of [...box.children]) if (item.dataset.key === key) item.remove();
}

// ---- formatting ----

/** A number for people: at most `digits` decimals, trailing zeros dropped. */
export function num(value, digits = 3) {
  if (value === null || value === undefined || value === "") return "–";
  if (typeof value === "number" && !Number.isFinite(value)) return "unknown"; // NaN, never shown
  const n = Number(value);
  if (!Number.isFinite(n)) return String(value);
  return String(Number(n.toFixed(digits)));
}

/** A value with its unit ("5 m", "0.18 m/s", "cw"). */
export function withUnit(value, unit, digits = 3) {
  if (value === null || value === undefined || value === "") return "–";
  if (typeof value !== "number" && !Number.isFinite(Number(value))) return String(value);
  return unit ? `${num(value, digits)} ${unit}` : num(value, digits);
}

/** A signed delta with unit ("+12 s", "-3.1 m"). */
export function delta(value, unit, digits = 1) {
  if (value === null || value === undefined) return "–";
  const n = Number(value);
  return `${n > 0 ? "+" : ""}${num(n, digits)}${unit ? ` ${unit}` : ""}`;
}

const SUFFIX_UNITS = [
  ["_mps", "m/s"], ["_deg", "deg"], ["_pct", "%"], ["_ms", "ms"], ["_bps", "b/s"],
  ["_bits", "bits"], ["_s", "s"], ["_m", "m"],
];

/** "duration_s" -> ["duration", "s"]: the unit convention of the API's key names. */
export function splitKey(key) {
  for (const [suffix, unit] of SUFFIX_UNITS) {
    if (key.endsWith(suffix)) return [key.slice(0, -suffix.length), unit];
  }
  return [key, ""];
}

/** Compact "key value unit" text of a flat object of unknown shape, units from key suffixes. */
export function summarize(obj, skip = []) {
  if (obj === null || obj === undefined) return "–";
  if (typeof obj !== "object") return String(obj);
  return Object.entries(obj)
    .filter(([k, v]) => !skip.includes(k) && v !== null && v !== undefined && typeof v !== "object")
    .map(([k, v]) => {
      const [name, unit] = splitKey(k);
      const label = name.replaceAll("_", " ");
      if (typeof v === "boolean") return `${label} ${v ? "yes" : "no"}`; // not "1" / "0"
      return `${label} ${withUnit(v, unit)}`;
    })
    .join(", ");
}

export function clock(iso) {
  if (!iso) return "–";
  const d = new Date(iso);
  return Number.isNaN(d.getTime()) ? String(iso) : d.toLocaleTimeString([], { hour12: false });
}

export function debounce(fn, ms) {
  let timer = null;
  const wrapped = (...args) => {
    clearTimeout(timer);
    timer = setTimeout(() => fn(...args), ms);
  };
  wrapped.cancel = () => clearTimeout(timer);
  return wrapped;
}

export function download(filename, text, type = "application/json") {
  const url = URL.createObjectURL(new Blob([text], { type }));
  const a = el("a", { href: url, download: filename, hidden: true });
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 1000);
}

/** A safe fragment of an id for data-testid ("j5 (unused)" -> "j5"). */
export function slug(text) {
  return String(text).replace(/\s*\(unused\)$/, "").replace(/[^A-Za-z0-9_.-]+/g, "-");
}

// ---- read-only gating ----

export const READ_ONLY_TIP = "read-only: open the URL with the operator token";
let writable = false;

export function canWrite() {
  return writable;
}

/** Enable or disable every [data-auth] control; call again after rendering new ones. */
export function applyAuth(canWriteNow = writable, root = document) {
  writable = canWriteNow;
  for (const node of root.querySelectorAll("[data-auth]")) {
    if (!("tip" in node.dataset)) node.dataset.tip = node.getAttribute("title") || "";
    node.disabled = !writable || node.dataset.off === "1";
    node.title = writable ? node.dataset.tip : READ_ONLY_TIP;
    node.classList.toggle("read-only", !writable);
  }
}

/** Change the hover text of an auth-gated control (shown while the page may write). */
export function setTip(node, tip) {
  node.dataset.tip = tip;
  if (writable) node.title = tip;
}

/** Disable an auth-gated control for another reason (off = true) without losing the gating. */
export function setOff(node, off) {
  node.dataset.off = off ? "1" : "0";
  applyAuth(writable, node.parentElement || document);
}

// ---- page events: one bus between the panels (chart, plots, prediction listen) ----
// "nemesys:session" {session}, "nemesys:preview" {preview, command} (null preview: cleared),
// "nemesys:telemetry" {msg} (a /ws telemetry message or GET /api/vehicle),
// "nemesys:vehicle" {msg} (the echo/active-path state).

/** Announce `name` ("session", "preview", ...) with `detail` to every listener on the page. */
export function emit(name, detail) {
  window.dispatchEvent(new CustomEvent(`nemesys:${name}`, { detail }));
}

/** Listen to `name` ("session", "preview", ...): `fn(detail)`. */
export function on(name, fn) {
  window.addEventListener(`nemesys:${name}`, (e) => fn(e.detail));
}

// ---- latitude and longitude ----

/** Degrees and decimal minutes as on a chart, exactly as backend/chart/geo.py dm() prints them:
 * dm(29.5316, true) -> "29°31.896'N", dm(-82.3031, false) -> "082°18.186'W"; "–" if unknown. */
export function dm(value, isLat) {
  if (value === null || value === undefined || value === "" || !Number.isFinite(Number(value))) return "–";
  const v = Number(value);
  const hemi = isLat ? (v >= 0 ? "N" : "S") : (v >= 0 ? "E" : "W");
  const a = Math.abs(v);
  let deg = Math.trunc(a);
  let minutes = (a - deg) * 60.0;
  let text = fixed3(minutes);
  if (Number(text) >= 60.0) {
    deg += 1;
    minutes = 0.0;
    text = fixed3(minutes);
  }
  return `${String(deg).padStart(isLat ? 2 : 3, "0")}°${text.padStart(6, "0")}'${hemi}`;
}

/** x.toFixed(3) with Python's rounding of an exact tie (half to even), as f"{x:.3f}" does. */
function fixed3(x) {
  const scaled = x * 1000;
  const floor = Math.floor(scaled);
  if (scaled - floor === 0.5 && floor % 2 === 0 && (floor + 0.5) / 1000 === x) return (floor / 1000).toFixed(3);
  return x.toFixed(3);
}

/** "29°31.896'N 082°18.186'W", or "–" when either is unknown. */
export function latLon(latDeg, lonDeg) {
  const lat = dm(latDeg, true);
  const lon = dm(lonDeg, false);
  return lat === "–" || lon === "–" ? "–" : `${lat} ${lon}`;
}
