// The replay's time slider, under this page's 3D view: a replayed dive (log.js) is loaded on
// its own clock (GET /api/dives/{id}/timeline); as the slider moves, the console says where the
// vehicle was and the command it was running then (PUT /api/replay/at, which also moves the
// vehicle marker in this page's 3D view), and the link events of the seconds before are listed
// from the timeline. Clear replay closes it.

import { api } from "./api.js";
import { $, el, num, notifyError, resolved, latLon } from "./ui.js";

/** Link events listed: those of the last WINDOW_S seconds up to the slider's time, newest first. */
const WINDOW_S = 10;
const MAX_EVENTS = 5;

const state = { dive: null, timeline: null, t: 0, busy: false, wanted: null };

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
  const dive = state.dive;
  try {
    const at = await api("/api/replay/at", { method: "PUT", body: { dive, t_s: t } });
    resolved("replay slider");
    if (dive === state.dive && at.t_s === state.t) renderAt(at);
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

/** Open the slider on dive `dive` (already drawn in this page's 3D view by log.js). */
export async function openReplay(dive) {
  let timeline;
  try {
    timeline = await api(`/api/dives/${encodeURIComponent(dive)}/timeline`);
  } catch (err) {
    notifyError(`replay of dive ${dive}`, err);
    return;
  }
  state.dive = dive;
  state.timeline = timeline;
  state.wanted = null;
  const slider = $("replay-slider");
  slider.min = String(Math.floor(timeline.from_t_s));
  slider.max = String(Math.ceil(timeline.duration_s));
  slider.value = "0";
  $("replay-title").textContent = `dive ${dive}`;
  const bar = $("replay-bar");
  bar.dataset.dive = String(dive);
  bar.hidden = false;
  bar.scrollIntoView({ block: "nearest" });
  seek(0);
}

function closeReplay() {
  state.dive = null;
  state.timeline = null;
  $("replay-bar").hidden = true;
}

export function initReplay() {
  $("replay-slider").addEventListener("input", (e) => state.timeline && seek(Number(e.target.value)));
  $("clear-replay").addEventListener("click", closeReplay); // view.js clears the 3D view
}
