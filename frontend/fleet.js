// A fleet on one ME link (issue 23, NEMESYS_VEHICLES): whether the console drives a fleet
// (GET /api/vehicles lists more than one vehicle, or addressed ones), the vehicle the operator
// selected, and the one transmitter's airtime budget (GET /api/transmitter). Every send,
// preview, prediction, retry and script step names its vehicle through withVehicle(); the Send
// button names the selected one ("Send to auv2…"): there is no implicit vehicle on Send. The
// single-vehicle panels (status, echo, belief, link, the chart's own vehicle) follow the
// selected vehicle: forSelected() tells app.js which news is theirs. Without a fleet nothing
// here changes the page, and every request goes as it always did.

import { api } from "./api.js";
import { $, el, emit, num, notifyError, resolved, setTip } from "./ui.js";

const RETRY_MS = 3000;
const TRANSMITTER_MS = 1000; // the budget counts down: asked again every second
const state = { on: false, names: [], addresses: new Map(), selected: null, timer: null };
let known; // resolves fleetKnown

/** Resolves to fleetOn() once loadFleet() has heard the console's vehicles: a read of one
 *  vehicle's (the plots' series) waits for it, so that a fleet's names its vehicle. */
export const fleetKnown = new Promise((resolve) => {
  known = resolve;
});

/** A fleet is configured (known once loadFleet() resolved). */
export function fleetOn() {
  return state.on;
}

/** The selected vehicle's name (null: no fleet). */
export function selectedVehicle() {
  return state.on ? state.selected : null;
}

export function fleetNames() {
  return state.names;
}

/** A vehicle's address (null: none, or not a vehicle of the fleet). */
export function addressOf(name) {
  return state.addresses.get(name) ?? null;
}

/** `body` naming `vehicle` (default: the selected one) with a fleet; as it is without one. */
export function withVehicle(body, vehicle = selectedVehicle()) {
  return state.on && vehicle ? { ...body, vehicle } : body;
}

/** Where the status panel reads its vehicle: /api/vehicle, or the selected one's. */
export function vehiclePath() {
  return state.on ? `/api/vehicles/${encodeURIComponent(state.selected)}` : "/api/vehicle";
}

/** The query naming the selected vehicle (a dive's track of it), or "" without a fleet. */
export function vehicleQuery() {
  return state.on ? `?vehicle=${encodeURIComponent(state.selected)}` : "";
}

/** Is this news (a /ws message, or a belief) about the selected vehicle? Always, without a fleet. */
export function forSelected(msg) {
  if (!state.on) return true;
  const name = msg && (msg.vehicle ?? (msg.belief && msg.belief.vehicle));
  return name === state.selected;
}

/** Ask the console for its vehicles (again every 3 s until it answers); resolves to fleetOn(). */
export async function loadFleet() {
  for (let attempt = 0; ; attempt++) {
    try {
      const list = await api("/api/vehicles");
      resolved("vehicles");
      if (Array.isArray(list)) configure(list);
      known(state.on);
      return state.on;
    } catch (err) {
      if (attempt === 0) notifyError("vehicles", err);
      await new Promise((resolve) => setTimeout(resolve, RETRY_MS));
    }
  }
}

function configure(list) {
  const fleet = list.length > 1 || list.some((v) => v && v.address !== null && v.address !== undefined);
  if (!fleet || state.on) return;
  state.on = true;
  state.names = list.map((v) => v.name);
  for (const v of list) state.addresses.set(v.name, v.address ?? null);
  document.body.classList.add("fleet");
  buildSelector();
  dressSurface();
  $("fleet-panel").hidden = false;
  emit("fleet", { vehicles: list }); // the rows and the chart's markers (fleet-rows.js, fleet-chart.js)
  selectVehicle(state.names[0]);
  pollTransmitter();
}

function optionText(name) {
  const address = addressOf(name);
  return address === null ? name : `${name} (address ${address})`;
}

function buildSelector() {
  const select = $("vehicle-select");
  select.replaceChildren(...state.names.map((n) => el("option", { value: n }, optionText(n))));
  select.addEventListener("change", () => selectVehicle(select.value));
  $("vehicle-field").hidden = false;
}

/** Select `name`: the Send button, the status panel and the chart follow it; the form's
 *  command is previewed again from where that vehicle is believed to be (authoring.js). */
export function selectVehicle(name) {
  if (!state.on || !state.names.includes(name)) return;
  state.selected = name;
  $("vehicle-select").value = name;
  const send = $("send-button");
  send.firstChild.textContent = `Send to ${name}… `;
  send.dataset.vehicle = name;
  setTip(send, `review the change, then send it to ${name} only (Ctrl+Enter); the vehicle selector above the pattern chooses another`);
  $("status-title").textContent = `Vehicle status: ${name}`;
  $("link-label").textContent = `${name} link`;
  emit("vehicle_selected", { vehicle: name });
}

/** The Surface button and its key become Surface all; each vehicle's own is in its row. */
function dressSurface() {
  const button = $("surface-button");
  button.firstChild.textContent = "SURFACE ALL (abort) ";
  button.dataset.fleet = "all";
  const row = document.querySelector('[data-testid="shortcut-surface"] td');
  if (row) {
    row.prepend(el("strong", { testid: "shortcut-surface-all" },
      "With a fleet: SURFACE ALL, one frame to every vehicle (address 0), which every vehicle accepts; each vehicle's own Surface is the button in its row. "));
  }
}

// ---- the one transmitter: how long until every vehicle's queued copies are out ----

async function pollTransmitter() {
  clearTimeout(state.timer);
  try {
    renderBudget(await api("/api/transmitter"));
  } catch (err) {
    renderBudget(null, err);
  }
  state.timer = setTimeout(pollTransmitter, TRANSMITTER_MS);
}

/** A command changed: the budget now, not at the next poll. */
export function transmitterChanged() {
  if (state.on) pollTransmitter();
}

function renderBudget(t, err = null) {
  const node = $("airtime-budget");
  if (!t) {
    node.textContent = `Transmitter: unknown (${(err && err.message) || "no answer"})`;
    node.className = "fleet-budget warn-text";
    return;
  }
  const budget = Number(t.airtime_budget_s) || 0;
  const parts = [budget > 0 ? `copies out in ${num(budget, 1)} s` : "no copies queued"];
  const repeating = Array.isArray(t.repeating_until_acknowledged) ? t.repeating_until_acknowledged : [];
  if (repeating.length) parts.push(`Surface repeating until acknowledged: ${repeating.join(", ")}`);
  if (t.connected === false) parts.push(`NOT CONNECTED${t.problems && t.problems.length ? `: ${t.problems.join("; ")}` : ""}`);
  node.textContent = `Transmitter: ${parts.join(" · ")}`;
  node.className = `fleet-budget${t.connected === false ? " warn-text" : ""}`;
  node.dataset.budget = String(budget);
}
