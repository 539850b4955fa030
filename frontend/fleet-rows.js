// A fleet's status rows (issue 23): one compact row per vehicle, each saying what the console
// says of it (GET /api/vehicles, then the /ws news naming it): its name and address, the
// command it is believed to run with p, where it is believed to be and on what basis, its
// link's health, depth and battery where the vehicle said them, and its own Surface button
// with that Surface's state (its belief's, as the header's banner reads it for one vehicle).
// Surface all (the header's button and its key) writes one record per vehicle: each row shows
// its own, and the banner counts those records by their state (the records' own, as the
// console announces them). Nothing here is worked out: every word is the console's.

import { api } from "./api.js";
import { candidateText } from "./belief.js";
import { upsertCommand } from "./commands.js";
import { pct } from "./delivery.js";
import { addressOf, fleetNames, fleetOn, selectVehicle, transmitterChanged } from "./fleet.js";
import { LEVEL, capabilityText } from "./link.js";
import { setSurfaceState, surfaceText } from "./surface.js";
import { $, el, emit, num, on, applyAuth, notifyError } from "./ui.js";

const RENDER_MS = 200; // telemetry comes at up to 10 Hz a vehicle: rows are redrawn at most 5 times a second
const LOW_BATTERY_PCT = 20;
const ALL_SHOWN_S = 60; // the banner's sum, after every record of Surface all ended
const vehicles = new Map(); // name -> {pose, status, link, belief, beliefAt, pending, nodes}
let renderTimer = null;
let all = null; // Surface all: {ids: Map(name -> record id) | null (not answered yet), endedAt}
const surfaces = new Map(); // a Surface record's id -> the newest of it (the POST's answer, /ws news)
const KEPT_SURFACES = 100;

const known = (v) => (typeof v === "number" && Number.isFinite(v) ? v : null);

/** Listen: the fleet's rows are built when fleet.js finds a fleet. */
export function initFleetRows() {
  on("fleet", ({ vehicles: list }) => build(list));
  on("vehicle_selected", ({ vehicle }) => {
    for (const row of document.querySelectorAll("#fleet-rows .fleet-row")) {
      const mine = row.dataset.vehicle === vehicle;
      row.classList.toggle("selected", mine);
      if (mine) row.setAttribute("aria-current", "true");
      else row.removeAttribute("aria-current");
    }
  });
  on("surface_all", onSurfaceAll);
}

/** The news of /ws (app.js passes it all): a vehicle's telemetry, link or belief; a command
 *  (the transmitter's budget changed); the page's connection lost ("close": the rows say they
 *  are old news) or opened again ("open": all reloaded). */
export function fleetNews(type, m) {
  if (!fleetOn() || !m) return;
  if (type === "command") {
    keepSurface(m.command);
    transmitterChanged();
    schedule();
    return;
  }
  if (type === "open" || type === "close") {
    $("fleet-stale").hidden = type === "open";
    $("fleet-rows").classList.toggle("stale", type === "close");
    if (type === "open") reload();
    return;
  }
  const name = type === "belief" ? m.belief && m.belief.vehicle : m.vehicle;
  const v = vehicles.get(name);
  if (!v) return;
  if (type === "telemetry") Object.assign(v, pick(m, ["pose", "status"]));
  else if (type === "link") v.link = m.link;
  else if (type === "belief") take(name, v, m.belief);
  schedule();
}

/** A vehicle as GET /api/vehicles or /api/vehicles/{name} gives it. */
export function fleetVehicle(view) {
  const v = view && vehicles.get(view.name);
  if (!v) return;
  Object.assign(v, pick(view, ["pose", "status", "link"]));
  take(view.name, v, view.belief, true);
  schedule();
}

function pick(m, keys) {
  return Object.fromEntries(keys.filter((k) => m[k] !== undefined && m[k] !== null).map((k) => [k, m[k]]));
}

/** A belief: the newest kept (seq), unless the page reloaded it after a reconnection. */
function take(name, v, belief, fresh = false) {
  if (!belief || typeof belief !== "object") return;
  if (!fresh && v.belief && Number.isFinite(belief.seq) && belief.seq < v.belief.seq) return;
  v.belief = belief;
  v.beliefAt = performance.now();
  emit("fleet_belief", { belief }); // the chart's markers (fleet-chart.js)
}

async function reload() {
  try {
    const list = await api("/api/vehicles");
    for (const view of Array.isArray(list) ? list : []) fleetVehicle(view);
  } catch (err) {
    notifyError("vehicles", err);
  }
}

function build(list) {
  const rows = $("fleet-rows");
  rows.before(el("p", { id: "fleet-stale", class: "warn", testid: "fleet-stale", role: "alert", hidden: true },
    "Console unreachable: the rows are what the page last heard."));
  rows.replaceChildren(...fleetNames().map((name) => {
    const nodes = rowNodes(name);
    vehicles.set(name, { pose: null, status: null, link: null, belief: null, beliefAt: 0, pending: null, nodes });
    return nodes.row;
  }));
  applyAuth(undefined, rows);
  for (const view of list) fleetVehicle(view);
  setInterval(schedule, 1000); // the Surface states' ages
}

/** A vehicle's row and the parts of it that change. */
function rowNodes(name) {
  const address = addressOf(name);
  const where = address === null ? "no address" : `address ${address}`;
  const nodes = {
    link: el("span", { class: "link-indicator level-unknown fleet-link", testid: `fleet-link-${name}` }),
    belief: el("div", { class: "fleet-belief", testid: `fleet-belief-${name}` }, "–"),
    facts: el("div", { class: "fleet-facts", testid: `fleet-facts-${name}` }, "–"),
    state: el("div", { class: "surface-state fleet-surface-state", testid: `fleet-surface-state-${name}`, hidden: true }),
  };
  nodes.row = el("li", { class: "fleet-row", testid: `fleet-row-${name}`, dataset: { vehicle: name } },
    el("div", { class: "fleet-head" },
      el("button", { type: "button", class: "fleet-name", testid: `fleet-select-${name}`, onclick: () => selectVehicle(name),
        title: `select ${name}: the next send, preview, prediction, retry and script step name it` }, name),
      el("span", { class: "muted", testid: `fleet-address-${name}` }, where),
      nodes.link,
      el("button", { type: "button", class: "small fleet-surface", testid: `fleet-surface-${name}`, dataset: { auth: "" },
        title: `Surface ${name} only (${where}); SURFACE ALL in the header surfaces every vehicle`, onclick: () => surfaceOne(name) },
      `Surface ${name}`)),
    nodes.belief, nodes.facts, nodes.state);
  return nodes;
}

// ---- Surface: one vehicle's, and Surface all's records ----

async function surfaceOne(name) {
  const v = vehicles.get(name);
  v.pending = { id: null };
  schedule();
  try {
    const r = await api("/api/surface", { method: "POST", body: { vehicle: name } });
    v.pending = { id: r && Number.isFinite(r.id) ? r.id : -1 };
    if (r && r.id !== undefined) upsertCommand(r);
  } catch (err) {
    v.pending = { error: `SURFACE ${name} NOT SENT: ${err.message}` };
    notifyError(`SURFACE ${name} failed`, err);
  }
  transmitterChanged();
  schedule();
}

/** A Surface record, kept unless an older copy of it (the log's order: updated_at). */
function keepSurface(r) {
  if (!r || r.kind !== "surface" || r.id === undefined) return;
  const old = surfaces.get(r.id);
  if (old && old.updated_at && r.updated_at && r.updated_at < old.updated_at) return;
  surfaces.set(r.id, r);
  while (surfaces.size > KEPT_SURFACES) surfaces.delete(surfaces.keys().next().value);
}

function onSurfaceAll({ phase, records }) {
  if (phase === "pressed") {
    all = { ids: null, endedAt: null };
    for (const v of vehicles.values()) v.pending = { id: null };
  } else if (phase === "answered") {
    for (const r of records) keepSurface(r);
    all = { ids: new Map(records.map((r) => [r.vehicle, r.id])), endedAt: null };
    for (const [name, v] of vehicles) v.pending = { id: all.ids.get(name) ?? -1 };
    transmitterChanged();
  } else {
    all = null;
    for (const v of vehicles.values()) v.pending = null;
    return; // surface.js says it was not sent
  }
  schedule();
}

/** A vehicle's Surface in words: the pressed one until its belief knows the record. */
function surfaceOf(v) {
  if (v.pending && v.pending.error) return { text: v.pending.error, kind: "error" };
  const s = v.belief && v.belief.surface;
  if (v.pending) {
    if (v.pending.id === null || !s || s.id === null || s.id < v.pending.id) return { text: "surfacing... sending", kind: "pending" };
    v.pending = null;
  }
  const said = surfaceText(s);
  if (!said) return null;
  const age = (Number(s.changed_s) || 0) + (performance.now() - v.beliefAt) / 1000;
  return said.kind === "pending" || age < said.shownS ? said : null;
}

/** The banner: Surface all's records, counted by their own state (a record not heard of: on
 *  its way, as the console answered it). */
function renderAll() {
  if (!all) return;
  if (!all.ids) {
    setSurfaceState("SURFACE ALL: surfacing... sending", "pending");
    return;
  }
  const counts = new Map();
  let pending = 0;
  for (const id of all.ids.values()) {
    const state = surfaces.get(id)?.state;
    const word = !state || state === "queued" || state === "transmitted" ? "surfacing..." : state;
    if (word === "surfacing...") pending++;
    counts.set(word, (counts.get(word) || 0) + 1);
  }
  const text = [...counts].map(([word, n]) => `${n} ${word.replace("_", " ")}`).join(", ");
  const ended = pending === 0;
  if (ended && all.endedAt === null) all.endedAt = performance.now();
  if (ended && performance.now() - all.endedAt > ALL_SHOWN_S * 1000) {
    all = null;
    setSurfaceState("", "");
    return;
  }
  const good = [...counts.keys()].every((w) => w === "acknowledged" || w === "sent");
  const kind = !ended ? "pending" : !good ? "error" : counts.has("sent") ? "sent" : "done";
  setSurfaceState(`SURFACE ALL (${all.ids.size} vehicles): ${text}`, kind);
}

// ---- rendering ----

function schedule() {
  if (renderTimer === null) renderTimer = setTimeout(render, RENDER_MS);
}

function render() {
  renderTimer = null;
  for (const v of vehicles.values()) renderRow(v);
  renderAll();
}

function positionText(p) {
  if (!p) return null;
  const where = `x ${num(p.x_m, 1)} m N, y ${num(p.y_m, 1)} m E`;
  if (p.source === "telemetry") return `${where} (fix)`;
  if (p.source === "dead_reckoning") return `${where} (dead-reckoned${known(p.sigma_m) !== null ? ` ± ${num(p.sigma_m, 1)} m` : ""})`;
  return `${where} (assumed: no fix)`;
}

function renderRow(v) {
  const { belief, facts, state } = v.nodes;
  const b = v.belief;
  const c = b && b.command;
  belief.textContent = c ? `${candidateText(c, b.two_way)} · p ${pct(c.p)}` : "–";
  belief.title = c ? c.reason : "";
  const s = v.status || {};
  const pose = v.pose || {};
  const depth = known(s.depth_m) ?? known(pose.z_m);
  const battery = known(s.battery_pct);
  const low = battery !== null && battery < LOW_BATTERY_PCT;
  facts.replaceChildren(...[
    positionText(b && b.position),
    depth === null ? null : `depth ${num(depth, 1)} m`,
    battery === null ? null : `battery ${num(battery, 0)} %${low ? " LOW" : ""}`,
  ].filter(Boolean).flatMap((text, i) => {
    // the position may wrap; depth and battery are kept whole
    const part = el("span", { class: i === 0 && b ? "" : `fleet-fact${low && text.startsWith("battery") ? " warn-text" : ""}` }, text);
    return i ? [" · ", part] : [part];
  }));
  facts.title = (b && b.position && b.position.basis) || "";
  renderLinkOf(v.nodes.link, v.link);
  const said = surfaceOf(v);
  state.hidden = !said;
  state.textContent = said ? said.text : "";
  state.className = `surface-state fleet-surface-state ${said ? said.kind : ""}`;
  state.dataset.kind = said ? said.kind : "";
}

/** The link's level as the header's indicator shows it (a glyph and a word), problems on hover. */
function renderLinkOf(node, l) {
  const level = l && ["green", "amber", "red"].includes(l.level) ? l.level : "unknown";
  const { glyph, word } = LEVEL[level];
  const problems = l && Array.isArray(l.problems) ? l.problems : [];
  const text = l ? word || "link ok" : "link ?";
  const title = l ? `${capabilityText(l)}${l.connected === false ? ", NOT CONNECTED" : ""}: ${problems.join("; ") || "no problems"}` : "no link state yet";
  const key = `${level}|${text}|${title}`;
  if (node.dataset.key === key) return;
  node.dataset.key = key;
  node.dataset.level = level;
  node.className = `link-indicator level-${level} fleet-link`;
  node.title = title;
  node.replaceChildren(el("span", { class: "link-dot", "aria-hidden": "true" }, glyph), el("span", { class: "link-text" }, text));
}
