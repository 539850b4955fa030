// The command lifecycle list (states, copies, delivery, Retry) and the echo mismatch; what
// the vehicle runs and the last sent are the console's belief (belief.js).

import { api } from "./api.js";
import { openRetry } from "./authoring.js";
import { RETRYABLE, copiesText, stateText } from "./delivery.js";
import { fleetOn } from "./fleet.js";
import { commandText } from "./form.js";
import { initSurface } from "./surface.js";
import { $, el, num, clock, notify, notifyError, applyAuth } from "./ui.js";

const MAX_ROWS = 200;
const commands = new Map(); // id -> record

export function initCommands({ wsSurface }) {
  initSurface({ wsSurface, record: upsertCommand });
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

/** Wire order, as the log's: when the first copy left (created, if none has yet), then id. */
function sortKey(r) {
  return `${r.first_sent_at || r.created_at || ""}|${String(r.id).padStart(12, "0")}`;
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
  // placed anew: its first copy leaving moves it to its place in wire order
  if (existing) existing.remove();
  const after = [...list.children].find((li) => sortKey(commands.get(li.dataset.id) || {}) < sortKey(r));
  list.insertBefore(row, after || null);
  while (list.children.length > MAX_ROWS) {
    commands.delete(list.lastElementChild.dataset.id);
    list.lastElementChild.remove();
  }
  applyAuth(undefined, row);
  if (!quiet && old && old.state !== r.state && r.state === "rejected") {
    // the row says why in full; the toast names the reason's code and points there
    const code = (r.ack && r.ack.reason) || "see its row";
    notify(`command ${r.id} (${r.pattern}) rejected: ${code}`, "warn");
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
    // the reason once: the record's reason already carries the vehicle's detail
    const reason = r.reason || [a.reason, a.detail].filter(Boolean).join(": ") || "no reason given";
    const named = a.field && reason.includes(a.field) ? "" : field;
    return `${reason}${named}${flipped}`;
  }
  return stateText(r);
}

/** "2/3 copies" in the row's head, with the frames handed to the link on hover. */
function copiesBadge(r, id) {
  const text = copiesText(r);
  if (!text) return r.attempts > 1 ? el("span", { class: "muted" }, `attempt ${r.attempts}`) : null;
  const worth = r.copies !== 1 || r.copies_sent !== 1 || r.state === "transmitted";
  if (!worth && !(r.attempts > 1)) return null;
  const attempts = Number.isFinite(r.attempts) ? `${r.attempts} frame${r.attempts === 1 ? "" : "s"} handed to the link (failed ones included)` : "";
  return el("span", { class: "muted cmd-copies", testid: `copies-${id}`, title: attempts }, text);
}

function renderRow(r) {
  const id = String(r.id);
  const children = [
    el("div", { class: "cmd-head" },
      el("span", { class: "cmd-time", title: r.created_at || "" }, clock(r.created_at)),
      el("strong", { class: "cmd-pattern" }, r.kind === "surface" ? "SURFACE" : r.pattern || "?"),
      el("span", { class: `state-badge st-${r.state}`, testid: `state-${id}` }, r.state || "?"),
      r.vehicle ? el("span", { class: "cmd-vehicle", testid: `command-vehicle-${id}`, title: `for ${r.vehicle} (a fleet's vehicle)` }, `to ${r.vehicle}`) : null,
      copiesBadge(r, id)),
    el("div", { class: "cmd-params muted" }, commandText({ pattern: r.pattern, params: r.params }), r.kind === "script" ? " [script]" : ""),
  ];
  const detail = detailText(r);
  if (detail) children.push(el("div", { class: `cmd-detail st-${r.state}`, testid: `command-detail-${id}` }, detail));
  if (RETRYABLE.has(r.state)) {
    children.push(el("button", { type: "button", class: "small", testid: `retry-${id}`, dataset: { auth: "" }, onclick: () => retry(r.id) }, "Retry"));
  }
  return el("li", { class: `command st-${r.state}`, testid: `command-${id}`, dataset: { id } }, ...children);
}

/** A retry is a new command, checked from where the vehicle is now: the confirm dialog of a
 *  send. A Surface is never checked nor confirmed (the abort, as its button): at once. */
async function retry(id) {
  const old = commands.get(String(id));
  if (!old) return;
  if (old.kind !== "surface" && old.pattern !== "surface") {
    await openRetry(old);
    return;
  }
  // a fleet: to the record's own vehicle, named
  const body = fleetOn() ? { vehicle: old.vehicle ?? null } : undefined;
  try {
    const r = await api(`/api/commands/${encodeURIComponent(id)}/retry`, { method: "POST", body });
    upsertCommand(r && r.id !== undefined ? r : { id, state: "queued" });
  } catch (err) {
    notifyError(`retry of command ${id}`, err);
  }
}

// ---- echo mismatch: the vehicle's echo differs from what it last accepted (the console's) ----

/** From GET /api/vehicle or a websocket "vehicle" message. */
export function renderEcho(v) {
  if (v && "echo_mismatch" in v) $("echo-mismatch").hidden = !v.echo_mismatch;
}
