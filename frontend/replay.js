// The replay's time slider, under this page's 3D view: a replayed dive (log.js) is loaded on
// its own clock (GET /api/dives/{id}/timeline); as the slider moves, the console says where the
// vehicle was and the command it was running then (PUT /api/replay/at, which also moves the
// vehicle marker in this page's 3D view), and the link events of the seconds before are listed
// from the timeline. Clear replay closes it. With a fleet a replay is one vehicle's, the one
// selected (its track, its commands, its events and those naming no vehicle, on its own clock:
// every request names it), the panel's title naming it; selecting another vehicle replays the
// same dive for that one.

import { api } from "./api.js";
import { fleetKnown, selectedVehicle } from "./fleet.js";
import { $, el, num, notifyError, on, resolved, latLon } from "./ui.js";

/** Link events listed: those of the last WINDOW_S seconds up to the slider's time, newest first. */
const WINDOW_S = 10;
const MAX_EVENTS = 5;

const state = { dive: null, vehicle: null, timeline: null, t: 0, busy: false, wanted: null, opens: 0 };

function commandOf(id) {
  const commands = (state.timeline && state.timeline.commands) || [];
  return commands.find((c) => c.id === id) || null;
}

function positionText(p) {
  if (!p) return "no track in this dive (no telemetry was heard)";
  const heading = Number.isFinite(p.heading_deg) ? `, heading ${num(p.heading_deg, 0)}°` : "";
  const geo = latLon(p.lat_deg, p.lon_deg);
  return `x ${num(p.x_m, 1)} m north, y ${num(p.y_m, 1)} m east, depth ${num(p.z_m, 1)} m${heading}${geo === "–" ? "" : ` (${geo})`}`;
}

function runningText(p) {
  if (!p) return "unknown (no telemetry)";
  const mode = p.mode ? ` · ${p.mode}` : "";
  if (!p.pattern) return `nothing${mode}`;
  const cmd = p.command_id == null ? null : commandOf(p.command_id);
  if (!cmd) return `${p.pattern} (not a command of this console's log)${mode}`;
  return `${cmd.text}${mode}`;
}

/** The link events of the WINDOW_S seconds up to `t`, or the last one before them. */
function renderEvents(t) {
  const events = (state.timeline && state.timeline.events) || [];
  const recent = events.filter((e) => e.t_s <= t && e.t_s > t - WINDOW_S).reverse().slice(0, MAX_EVENTS);
  const list = $("replay-events");
  const item = (e) => el("li", { dataset: { kind: e.kind, t: String(e.t_s) } }, `${num(e.t_s - t, 1)} s: ${e.text}`);
  if (recent.length) {
    list.replaceChildren(...recent.map(item));
    return;
  }
  const before = events.filter((e) => e.t_s <= t);
  const last = before[before.length - 1];
  list.replaceChildren(
    el("li", { class: "hint" }, last ? `none in the ${WINDOW_S} s before; the last ${num(t - last.t_s, 0)} s before: ${last.text}` : "none yet"),
  );
}

function renderAt(at) {
  const p = at && at.position;
  $("replay-position").textContent = positionText(p);
  $("replay-command").textContent = runningText(p);
  const bar = $("replay-bar");
  bar.dataset.t = String(at.t_s);
  bar.dataset.commandId = p && p.command_id != null ? String(p.command_id) : "";
}

/** Ask the console for the vehicle at the slider's time; one request at a time, the latest wins. */
async function seek(t) {
  state.t = t;
  $("replay-time").textContent = `${num(t, 0)} s of ${num(state.timeline.duration_s, 0)} s`;
  renderEvents(t);
  if (state.busy) {
    state.wanted = t;
    return;
  }
  state.busy = true;
  const { dive, vehicle } = state;
  const body = vehicle ? { dive, t_s: t, vehicle } : { dive, t_s: t };
  try {
    const at = await api("/api/replay/at", { method: "PUT", body });
    resolved("replay slider");
    if (dive === state.dive && vehicle === state.vehicle && at.t_s === state.t) renderAt(at);
  } catch (err) {
    notifyError("replay slider", err);
  } finally {
    state.busy = false;
    if (state.wanted !== null && dive === state.dive) {
      const next = state.wanted;
      state.wanted = null;
      seek(next);
    }
  }
}

/** Draw dive `dive` in this page's 3D view (POST /api/dives/{id}/replay; a fleet's: of the
 *  selected vehicle, once the page knows whether there is a fleet); resolves to the vehicle
 *  drawn (null: no fleet), for openReplay(). */
export async function drawReplay(dive) {
  const fleet = await fleetKnown;
  const vehicle = fleet ? selectedVehicle() : null;
  const which = vehicle ? `?vehicle=${encodeURIComponent(vehicle)}` : "";
  await api(`/api/dives/${encodeURIComponent(dive)}/replay${which}`, { method: "POST" });
  return vehicle;
}

/** Open the slider on dive `dive` (already drawn in this page's 3D view by drawReplay()), of
 *  the fleet's `vehicle` (null: no fleet). */
export async function openReplay(dive, vehicle = null) {
  const open = ++state.opens;
  const which = vehicle ? `?vehicle=${encodeURIComponent(vehicle)}` : "";
  let timeline;
  try {
    timeline = await api(`/api/dives/${encodeURIComponent(dive)}/timeline${which}`);
  } catch (err) {
    notifyError(`replay of dive ${dive}`, err);
    return;
  }
  if (open !== state.opens) return; // opened again meanwhile (another dive, another vehicle)
  state.dive = dive;
  state.vehicle = vehicle;
  state.timeline = timeline;
  state.wanted = null;
  const slider = $("replay-slider");
  slider.min = String(Math.floor(timeline.from_t_s));
  slider.max = String(Math.ceil(timeline.duration_s));
  slider.value = "0";
  $("replay-title").textContent = vehicle ? `dive ${dive}: ${vehicle}` : `dive ${dive}`;
  const bar = $("replay-bar");
  bar.dataset.dive = String(dive);
  if (vehicle) bar.dataset.vehicle = vehicle;
  else delete bar.dataset.vehicle;
  bar.hidden = false;
  bar.scrollIntoView({ block: "nearest" });
  seek(0);
}

function closeReplay() {
  state.opens++; // a timeline still on its way opens nothing
  state.dive = null;
  state.vehicle = null;
  state.timeline = null;
  $("replay-bar").hidden = true;
}

/** Another vehicle of the fleet selected while a dive is replayed: the same dive, of that one. */
async function replayOf(vehicle) {
  const dive = state.dive;
  if (dive === null || !state.vehicle || vehicle === state.vehicle) return;
  try {
    const drawn = await drawReplay(dive);
    resolved(`replay of dive ${dive}`);
    if (dive === state.dive) openReplay(dive, drawn);
  } catch (err) {
    notifyError(`replay of dive ${dive}`, err);
  }
}

export function initReplay() {
  $("replay-slider").addEventListener("input", (e) => state.timeline && seek(Number(e.target.value)));
  $("clear-replay").addEventListener("click", closeReplay); // view.js clears the 3D view
  on("vehicle_selected", ({ vehicle }) => replayOf(vehicle)); // a fleet's (fleet.js)
}
