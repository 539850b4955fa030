// The command lifecycle list, the SURFACE abort and the echo check.

import { api, ApiError } from "./api.js";
import { commandText } from "./form.js";
import { $, el, num, clock, notify, notifyError, applyAuth } from "./ui.js";

const MAX_ROWS = 200;
const RETRYABLE = new Set(["timed_out", "failed", "rejected"]);
const commands = new Map(); // id -> record
let surfaceId = null; // the surface command being repeated, until acknowledged
let surfaceWaiting = false; // POST /api/surface sent, no record yet
let surfaceClickedAt = 0;
let lastSent = null;
let sendSurfaceOverWs = null;

export function initCommands({ wsSurface }) {
  sendSurfaceOverWs = wsSurface;
  $("surface-button").addEventListener("click", surface);
}

export async function loadCommands() {
  try {
    const rows = await api("/api/commands?limit=50");
    const list = Array.isArray(rows) ? rows : (rows && rows.commands) || [];
    for (const r of list.slice().reverse()) upsertCommand(r, { quiet: true });
  } catch (err) {
    notifyError("could not load the command log", err);
  }
}

function sortKey(r) {
  return `${r.created_at || ""}|${String(r.id).padStart(12, "0")}`;
}

/** A record from the log, the websocket or a POST: add or update its row. */
export function upsertCommand(record, { quiet = false } = {}) {
  if (!record || record.id === undefined || record.id === null) return;
  const key = String(record.id);
  const old = commands.get(key);
  if (old && old.updated_at && record.updated_at && record.updated_at < old.updated_at) return;
  commands.set(key, { ...(old || {}), ...record });
  const r = commands.get(key);
  const list = $("command-list");
  const row = renderRow(r);
  const existing = list.querySelector(`[data-testid="command-${CSS.escape(String(r.id))}"]`);
  if (existing) existing.replaceWith(row);
  else {
    const after = [...list.children].find((li) => sortKey(commands.get(li.dataset.id) || {}) < sortKey(r));
    list.insertBefore(row, after || null);
    while (list.children.length > MAX_ROWS) {
      commands.delete(list.lastElementChild.dataset.id);
      list.lastElementChild.remove();
    }
  }
  applyAuth(undefined, row);
  trackSurface(r);
  if (r.kind !== "surface" && ["transmitted", "acknowledged"].includes(r.state)) {
    if (!lastSent || sortKey(r) >= sortKey(lastSent)) setLastSent(r);
  }
  if (!quiet && old && old.state !== r.state && r.state === "rejected") {
    notify(`command ${r.id} (${r.pattern}) rejected: ${r.reason || "no reason given"}`, "warn");
  }
}

function ackText(r) {
  const a = r.ack || {};
  const parts = [];
  if (a.corrected_bits != null) parts.push(`corrected ${a.corrected_bits} bit${a.corrected_bits === 1 ? "" : "s"}`);
  if (a.channel_flipped_bits != null) parts.push(`channel flipped ${a.channel_flipped_bits}`);
  if (a.sync_errors) parts.push(`sync errors ${a.sync_errors}`);
  if (a.decode_latency_ms != null) parts.push(`decode ${num(a.decode_latency_ms, 3)} ms`);
  if (a.replan_latency_ms != null) parts.push(`replan ${num(a.replan_latency_ms, 3)} ms`);
  if (a.duplicate) parts.push("duplicate (already active)");
  return parts.join(", ");
}

function detailText(r) {
  if (r.state === "acknowledged") return ackText(r) || "acknowledged";
  if (r.state === "rejected" || r.state === "failed") {
    const a = r.ack || {};
    const field = a.field ? ` (field ${a.field})` : "";
    const flipped = a.channel_flipped_bits != null ? `; channel flipped ${a.channel_flipped_bits} bits` : "";
    return `${r.reason || a.reason || "no reason given"}${field}${a.detail ? `: ${a.detail}` : ""}${flipped}`;
  }
  if (r.state === "timed_out") return "no acknowledgement (frame lost or out of range?)";
  return "";
}

function renderRow(r) {
  const id = String(r.id);
  const children = [
    el("div", { class: "cmd-head" },
      el("span", { class: "cmd-time", title: r.created_at || "" }, clock(r.created_at)),
      el("strong", { class: "cmd-pattern" }, r.kind === "surface" ? "SURFACE" : r.pattern || "?"),
      el("span", { class: `state-badge st-${r.state}`, testid: `state-${id}` }, r.state || "?"),
      r.attempts > 1 ? el("span", { class: "muted" }, `attempt ${r.attempts}`) : null),
    el("div", { class: "cmd-params muted" }, commandText({ pattern: r.pattern, params: r.params }), r.kind === "script" ? " [script]" : ""),
  ];
  const detail = detailText(r);
  if (detail) children.push(el("div", { class: `cmd-detail st-${r.state}`, testid: `command-detail-${id}` }, detail));
  if (RETRYABLE.has(r.state) && r.kind !== "surface") {
    children.push(el("button", { type: "button", class: "small", testid: `retry-${id}`, dataset: { auth: "" }, onclick: () => retry(r.id) }, "Retry"));
  }
  return el("li", { class: `command st-${r.state}`, testid: `command-${id}`, dataset: { id } }, ...children);
}

async function retry(id) {
  try {
    const r = await api(`/api/commands/${encodeURIComponent(id)}/retry`, { method: "POST" });
    upsertCommand(r && r.id !== undefined ? r : { id, state: "queued" });
  } catch (err) {
    notifyError(`retry of command ${id}`, err);
  }
}

// ---- SURFACE ----

async function surface() {
  setSurfaceState("surfacing... repeating until acknowledged", "pending");
  surfaceWaiting = true;
  surfaceClickedAt = Date.now();
  try {
    const r = await api("/api/surface", { method: "POST" });
    if (r && r.id !== undefined) {
      surfaceId = r.id;
      upsertCommand(r);
    }
  } catch (err) {
    if (err instanceof ApiError && err.status === 0 && sendSurfaceOverWs && sendSurfaceOverWs()) {
      notify("REST unreachable: SURFACE sent over the websocket", "warn");
      return;
    }
    surfaceWaiting = false;
    setSurfaceState(`SURFACE NOT SENT: ${err.message}`, "error");
    notifyError("SURFACE failed", err);
  }
}

function trackSurface(r) {
  const isSurface = r.kind === "surface" || r.pattern === "surface";
  if (!isSurface) return;
  const created = Date.parse(r.created_at || "");
  const recent = Number.isNaN(created) || created >= surfaceClickedAt - 60000;
  if (surfaceId === null && surfaceWaiting && recent) surfaceId = r.id;
  if (surfaceId === null || String(r.id) !== String(surfaceId)) return;
  if (r.state === "acknowledged") {
    surfaceWaiting = false;
    surfaceId = null;
    setSurfaceState("surface acknowledged", "done");
    setTimeout(() => { if (surfaceId === null && !surfaceWaiting) setSurfaceState("", ""); }, 15000);
  } else if (r.state === "failed" || r.state === "rejected") {
    setSurfaceState(`surface ${r.state}: ${r.reason || ""} (still repeating? press again if needed)`, "error");
  } else {
    setSurfaceState("surfacing... repeating until acknowledged", "pending");
  }
}

function setSurfaceState(text, kind) {
  const box = $("surface-state");
  box.textContent = text;
  box.hidden = !text;
  box.className = `surface-state ${kind}`;
}

// ---- echo check ----

function setLastSent(cmd) {
  lastSent = cmd;
  $("echo-sent").textContent = cmd ? commandText(cmd) : "–";
}

/** From GET /api/vehicle or a websocket "vehicle" message. */
export function renderEcho(v) {
  if (!v) return;
  if ("active" in v) $("echo-active").textContent = v.active ? commandText(v.active) : "nothing (idle)";
  if (v.last_sent) setLastSent(v.last_sent);
  if ("echo_mismatch" in v) $("echo-mismatch").hidden = !v.echo_mismatch;
}
