// The vehicle link (not the page's websocket to the console): what it can do (acknowledgements,
// telemetry) and how it is doing (green / amber / red with named problems). Shown in the header
// indicator and the status panel's link row; other panels ask it whether acknowledgements come
// and how many copies the console would choose. The row's "Test link" button checks the link
// now without sending a frame (POST /api/link/test).

import { api } from "./api.js";
import { berText, age } from "./delivery.js";
import { $, canWrite, el, notify, num, READ_ONLY_TIP, resolved, withUnit } from "./ui.js";

const CAPABILITY = {
  acks_and_telemetry: "acks + telemetry",
  telemetry_only: "telemetry only, no acks",
  none: "one-way (no acks)",
  unknown: "unknown",
};
// colour is never the only cue: a glyph in the dot and a word in the text too
export const LEVEL = {
  green: { glyph: "✓", word: "" },
  amber: { glyph: "!", word: "degraded" },
  red: { glyph: "✕", word: "failing" },
  unknown: { glyph: "?", word: "" },
};

let vehicleLink = null; // GET /api/vehicle "link" or a websocket "link" message
let linkAt = 0; // performance.now() when it came
let reachable = true; // the page's websocket to the console is open
let staleTicker = null;
let sessionLink = null; // GET /api/session "link"
let radio = null; // the simulator's own view of the channel (telemetry status.link)
const listeners = new Set();

/** fn() after every change of what the link can do (acknowledges, default copies). */
export function onLinkChange(fn) {
  listeners.add(fn);
}

function changed() {
  for (const fn of listeners) {
    try {
      fn();
    } catch (err) {
      console.warn("link listener failed", err);
    }
  }
}

/** True / false when known, null when the console has not said yet. */
export function linkAcknowledges() {
  for (const l of [vehicleLink, sessionLink]) {
    if (l && typeof l.acknowledges === "boolean" && l.capability !== "unknown") return l.acknowledges;
  }
  return null;
}

/** The copies the console would choose for a command now (null when unknown). */
export function autoCopies() {
  return vehicleLink && Number.isFinite(vehicleLink.copies) ? vehicleLink.copies : null;
}

/** The copies of a SURFACE on this link (null: repeated until acknowledged, or unknown). */
export function autoSurfaceCopies() {
  return vehicleLink && Number.isFinite(vehicleLink.surface_copies) ? vehicleLink.surface_copies : null;
}

/** The latest link object (read-only use). */
export function currentLink() {
  return vehicleLink;
}

function capabilityOf(l) {
  if (!l) return "unknown";
  if (l.capability) return l.capability;
  if (l.acknowledges === true) return "acks_and_telemetry"; // an older console: guess from acks
  return "unknown";
}

export function capabilityText(l) {
  const cap = capabilityOf(l);
  return CAPABILITY[cap] || cap.replaceAll("_", " ");
}

function levelOf(l) {
  if (!l) return "unknown";
  if (["green", "amber", "red"].includes(l.level)) return l.level;
  if (l.connected === false) return "red";
  return "unknown";
}

function problemsOf(l) {
  const problems = l && Array.isArray(l.problems) ? l.problems.map(String) : [];
  if (l && l.connected === false && !problems.length) problems.push("not connected to the vehicle");
  return problems;
}

/** From GET /api/session: what the link can do, before the first vehicle state arrives. */
export function setSessionLink(link) {
  sessionLink = link && typeof link === "object" ? link : null;
  if (!vehicleLink) renderIndicator(sessionLink);
  changed();
}

let logRefusal = null; // the header's line while the mission log is unreachable

/** The mission log's database out of reach (link.mission_log): a line in the header's
 *  message row until it is back ("mission log unreachable — sends refused"). */
function renderMissionLog(reach) {
  const down = reach && reach.reachable === false;
  const text = down ? `mission log unreachable — sends refused (${reach.problem || "no answer"})` : null;
  if (text === logRefusal) return; // unchanged: told once, not every second
  logRefusal = text;
  if (text) notify(text, "error", "mission-log");
  else resolved("mission-log");
}

/** A console without a transmitter (target relay): "relay via <the console holding it>"
 *  (link.relay), or that none holds one; "" on a console that transmits. */
export function relayText(l) {
  const r = l && l.relay;
  if (!r || typeof r !== "object") return "";
  return r.via ? `relay via ${r.via}` : "relay: no console holds the transmitter";
}

/** The transmitting console's link as the relay console last read it, for the status row. */
function relayFacts(r) {
  if (!r.via) return "no console holding the transmitter is on the mission log";
  const seen = typeof r.seen_age_s === "number" ? `seen ${age(r.seen_age_s)}` : "";
  if (!r.fresh) return `${r.via} NOT SEEN (${seen || "never"}): commands cannot be sent`;
  const link = [r.target, r.connected === false ? "NOT CONNECTED" : "connected", r.level]
    .filter(Boolean).join(", ");
  return `its link: ${link}; ${seen}`;
}

/** A mission log event worth a line in the message row: a relayed command refused by the
 *  console holding the transmitter (every console's pages get it). */
export function renderLogEvent(e) {
  if (e && e.kind === "relay" && e.detail) notify(String(e.detail), "warn", "relay");
}

/** Who is in control of a vehicle changed (consoles sharing one mission log: a websocket
 *  "control" message), said in the message row, with a request waiting for the owner (its
 *  Grant and Refuse buttons are in the Control panel: control.js). */
export function renderControl(c) {
  if (!c || typeof c !== "object" || c.implicit) return;
  const who = c.console ? `console ${c.console} (operator ${c.operator})` : "nobody";
  let text = `control of ${c.vehicle}: ${who}`;
  const r = c.request;
  if (r) text += `; console ${r.console} (operator ${r.operator}) asks for it: grant or refuse`;
  notify(text, r ? "warn" : "info", "control");
}

/** From GET /api/vehicle or a websocket "link" message. */
export function renderLink(link) {
  if (!link || typeof link !== "object") return;
  renderMissionLog(link.mission_log);
  vehicleLink = link;
  linkAt = performance.now();
  renderIndicator(link);
  renderRow();
  changed();
}

/** The page's connection to the console opened (true) or closed (false): closed, what the
 *  page last heard of the vehicle link is old news, and says so (its ages keep counting). */
export function setConsoleReachable(ok) {
  reachable = ok;
  clearInterval(staleTicker);
  staleTicker = ok ? null : setInterval(renderRow, 1000);
  renderIndicator(vehicleLink || sessionLink);
  renderRow();
}

/** The simulator's channel facts from telemetry (status.link); null when absent. */
export function setRadio(r) {
  radio = r && typeof r === "object" ? r : null;
  renderRow();
}

function renderIndicator(l) {
  const node = $("link-indicator");
  if (!node) return;
  const level = l && reachable ? levelOf(l) : "unknown";
  const problems = problemsOf(l);
  const { glyph, word } = LEVEL[level];
  const relay = relayText(l);
  let text = l ? `${relay ? `${relay} · ` : ""}${capabilityText(l)}${word ? ` – ${word}` : ""}` : "waiting…";
  let title = l ? (problems.length ? problems.join("\n") : "no problems") : "no vehicle link state yet";
  if (!reachable) {
    text = "unknown (console unreachable)";
    title = "this page lost its connection to the console: the vehicle link's state is not known";
  }
  const key = `${level}|${text}|${title}`;
  if (node.dataset.key === key) return; // unchanged: a live region must not repeat itself every second
  node.dataset.key = key;
  node.className = `link-indicator level-${level}`;
  node.title = title;
  node.setAttribute("aria-label", `vehicle link: ${text}; ${title.replaceAll("\n", "; ")}`);
  node.replaceChildren(
    el("span", { class: "link-dot", "aria-hidden": "true" }, glyph),
    el("span", { class: "link-text", testid: "link-text" }, text));
}

function framesText(f) {
  if (!f || typeof f !== "object" || !f.frames) return "";
  const parts = [];
  if (f.acknowledged) parts.push(`${f.acknowledged} acked`);
  if (f.sent) parts.push(`${f.sent} sent without ack`);
  if (f.rejected) parts.push(`${f.rejected} rejected`);
  if (f.timed_out) parts.push(`${f.timed_out} timed out`);
  return `${f.frames} frame${f.frames === 1 ? "" : "s"}${parts.length ? `: ${parts.join(", ")}` : ""}`;
}

function radioText(r) {
  if (!r) return [];
  const parts = [];
  if (r.in_range !== undefined) parts.push(r.in_range ? "in range" : "OUT OF RANGE");
  if (r.distance_m != null) parts.push(`${num(r.distance_m, 1)} m of ${r.range_m == null ? "unlimited" : withUnit(r.range_m, "m", 0)} range`);
  if (r.frames_in != null) parts.push(`frames in ${r.frames_in}, lost ${r.frames_lost ?? 0}`);
  return parts;
}

function renderRow() {
  const node = $("status-link");
  if (!node) return;
  const l = vehicleLink;
  const facts = [];
  const since = (performance.now() - linkAt) / 1000; // the ages count on since it came
  const later = (a) => (typeof a === "number" && Number.isFinite(a) ? a + since : a);
  if (!reachable && l) facts.push(`console unreachable: the vehicle link as of ${Math.round(since)} s ago`);
  if (l) {
    if (l.relay && typeof l.relay === "object") facts.push(`${relayText(l)} (${relayFacts(l.relay)})`);
    facts.push(capabilityText(l));
    if (l.connected !== undefined && reachable) facts.push(l.connected ? "connected" : "NOT CONNECTED");
    const recent = framesText(l.frames && l.frames.recent);
    if (recent) facts.push(`recent frames: ${recent}`);
    if (l.acknowledges && l.last_ack_age_s !== undefined) facts.push(`last ack ${age(later(l.last_ack_age_s))}`);
    if (l.telemetry && l.last_telemetry_age_s !== undefined) {
      const via = l.relay && l.relay.telemetry_via ? ` via ${l.relay.telemetry_via}'s log` : "";
      facts.push(`telemetry${via} ${age(later(l.last_telemetry_age_s))}`);
    }
    if (l.ber != null) facts.push(`BER ${berText(l.ber)}${berSourceText(l)}`);
    if (Number.isFinite(l.copies)) facts.push(`${l.copies} cop${l.copies === 1 ? "y" : "ies"} per command`);
    if (l.unknown_values) facts.push(`${l.unknown_values} unknown telemetry values`);
  }
  facts.push(...radioText(radio));
  const problems = problemsOf(l);
  const level = l ? levelOf(l) : "unknown";
  const bad = !reachable || level === "red" || level === "amber" || (radio && radio.in_range === false);
  node.className = bad ? "warn-text" : "";
  const estimate = l ? estimateNode(l) : null;
  node.replaceChildren(
    el("span", { class: "link-facts" }, facts.join(" · ") || "–"),
    estimate,
    ...problems.map((p) => el("span", { class: "link-problem", testid: "link-problem" }, p)));
}

/** Where the BER the copies follow comes from (the console's ber_source and copies_from). */
function berSourceText(l) {
  if (l.ber_source === "emulated") return " (emulated channel)";
  if (l.ber_source === "estimate_upper") return " (upper end of the estimate)";
  if (l.ber_source !== "assumed") return "";
  if (l.copies_from === "estimate_upper") return " (assumed: no estimate yet for the chosen upper end)";
  return " (assumed)";
}

/** A rate to two significant digits, as typed: 0.0093, 0.013, 0. */
function rate(x) {
  return x === 0 ? "0" : String(Number(x.toPrecision(2)));
}

/** "BER ≈ 0.009 (95 % 0.006–0.013, 214 frames)", "no estimate yet (3 frames)", or "". */
export function estimateText(c, acknowledges = true) {
  if (!c || typeof c !== "object" || !Number.isFinite(c.frames)) return "";
  const frames = `${c.frames} frame${c.frames === 1 ? "" : "s"}`;
  if ([c.ber, c.low, c.high].every(Number.isFinite)) {
    const pct = Math.round(100 * (Number.isFinite(c.confidence) ? c.confidence : 0.95));
    return `BER ≈ ${rate(c.ber)} (${pct} % ${rate(c.low)}–${rate(c.high)}, ${frames})`;
  }
  if (!c.frames && !acknowledges) return "none (no acknowledgements on this link)";
  return `no estimate yet (${frames})`;
}

/** The estimate from the acknowledgements, on a line of its own (null: an older console). */
function estimateNode(l) {
  const text = estimateText(l.channel, l.acknowledges !== false);
  if (!text) return null;
  const c = l.channel;
  const refused = c.not_decoded ? `, ${c.not_decoded} of them refused by the decoder` : "";
  const title = "estimated from the dive's acknowledgements: the corrected bits and sync errors " +
    `of each decoded frame${refused}; frames with no acknowledgement are not counted; ` +
    `independent bit errors assumed${c.ber == null ? `; an estimate from ${c.min_frames} frames` : ""}`;
  return el("span", { class: "link-estimate", testid: "link-ber-estimate", title },
    `estimated: ${text}`);
}

// ---- "Test link" (POST /api/link/test: no frame is sent) ----

let testing = false;

export function initLinkTest() {
  const button = $("link-test");
  if (button) button.addEventListener("click", testLink);
}

function showTest(text, error = false) {
  const node = $("link-test-result");
  node.textContent = text;
  node.className = error ? "error" : "hint";
  node.hidden = !text;
}

/** "link OK: modem tcp://gw:4001 ok; no frame sent" or what failed and why. */
export function linkTestText(result) {
  const checks = result && Array.isArray(result.checks) ? result.checks : [];
  const parts = checks.map((c) => c.ok
    ? `${c.what} ${c.target} ok`
    : `${c.what} ${c.target}: ${c.reason || "failed"}${c.detail ? ` (${c.detail})` : ""}`);
  return `${result && result.ok ? "link OK" : "link FAILED"}: ${parts.join("; ") || "nothing to check"}; no frame sent`;
}

async function testLink() {
  if (testing) return;
  if (!canWrite()) {
    showTest(READ_ONLY_TIP, true);
    return;
  }
  testing = true;
  showTest("testing…");
  try {
    const result = await api("/api/link/test", { method: "POST" });
    if (result && result.link) renderLink(result.link);
    showTest(linkTestText(result), !(result && result.ok));
  } catch (err) {
    if (err && err.name === "AbortError") return;
    showTest(`not tested: ${(err && err.message) || err}`, true);
  } finally {
    testing = false;
  }
}
