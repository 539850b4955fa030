// The console's belief of the vehicle (GET /api/vehicle "belief", the /ws "belief" message):
// what it probably runs and how sure that is, the runner-up, where it probably is, the last
// command sent. The page shows it as it comes and decides nothing itself; the chart (its
// layers are made here) and the SURFACE banner get it as the "belief" page event.

import { pct } from "./delivery.js";
import { commandText } from "./form.js";
import { $, el, num, emit } from "./ui.js";

let current = null; // the belief shown
let receivedAt = 0; // performance.now() when it came
let reachable = true; // the page's websocket to the console is open
let ticker = null;

/** The belief shown (null: none yet). */
export function currentBelief() {
  return current;
}

/** A belief from the websocket or GET /api/vehicle: a late answer never replaces a newer one
 *  (``seq``), except after a reconnection (the console may have restarted). */
export function renderBelief(b) {
  if (!b || typeof b !== "object") return;
  if (current && reachable && Number.isFinite(b.seq) && b.seq < current.seq) return;
  current = b;
  receivedAt = performance.now();
  render();
  emit("belief", { belief: b });
}

/** The page's connection to the console opened (true) or closed (false). */
export function setBeliefReachable(ok) {
  reachable = ok;
  if (!ok && current) current = { ...current, seq: -1 }; // whatever comes next is newer
  clearInterval(ticker);
  ticker = ok ? null : setInterval(render, 1000);
  render();
}

/** Another vehicle of a fleet was selected: its belief replaces this one, whatever its seq. */
export function forgetBelief() {
  current = null;
}

/** "unknown (no telemetry)", "nothing (idle)", "circle: speed 0.18 m/s, ...". */
export function candidateText(c, twoWay) {
  if (!c) return "–";
  if (c.kind === "unknown") return twoWay ? "unknown (nothing heard yet)" : "unknown (no telemetry)";
  if (!c.pattern) return "nothing (idle, as the vehicle reports)";
  const text = commandText(c);
  return c.id == null ? `${text} (not a command of this console)` : text;
}

function pText(p) {
  return `p ${pct(p)}`;
}

function render() {
  const b = current;
  if (!b) return;
  const stale = reachable ? "" : `as of ${num((performance.now() - receivedAt) / 1000, 0)} s ago (console unreachable): `;
  const c = b.command;
  const active = $("echo-active");
  active.title = c ? c.reason : "";
  active.replaceChildren(
    stale,
    el("span", { testid: "belief-command" }, candidateText(c, b.two_way)),
    " ",
    el("span", { class: "muted belief-p", testid: "belief-p" }, c ? pText(c.p) : ""),
  );
  const r = b.runner_up;
  const runner = $("belief-runner-up");
  runner.title = r ? r.reason : "";
  runner.replaceChildren(r ? `${candidateText(r, b.two_way)} (${pText(r.p)})` : "none");
  $("echo-sent").textContent = b.last_sent ? commandText(b.last_sent) : "–";
  renderPosition(b.position, stale);
}

function renderPosition(p, stale) {
  const node = $("belief-position");
  if (!p) {
    node.textContent = "–";
    return;
  }
  node.title = p.basis || "";
  node.dataset.source = p.source;
  const where = `x ${num(p.x_m, 1)} m north, y ${num(p.y_m, 1)} m east, depth ${num(p.z_m, 1)} m`;
  const ring = Number.isFinite(p.sigma_m) ? ` ± ${num(p.sigma_m, 1)} m` : "";
  let how;
  if (p.source === "telemetry") how = "the last fix (telemetry)";
  else if (p.source === "dead_reckoning") how = `dead-reckoned, ${num(p.age_s, 0)} s since the last fix`;
  else how = "assumed: no fix ever (hover for what was assumed)";
  node.className = p.source === "telemetry" ? "" : "warn-text";
  node.textContent = `${stale}${where}${ring}: ${how}`;
}

/** The chart's layers (Leaflet ``L``) for the believed position when it is not the fix: its
 *  uncertainty ring (dead-reckoned) and a labelled marker (dead-reckoned, or assumed); none
 *  otherwise, or without lat/lon (no datum). */
export function beliefLayers(L, belief) {
  const p = belief && belief.position;
  if (!p || p.source === "telemetry" || !Number.isFinite(p.lat_deg) || !Number.isFinite(p.lon_deg)) return [];
  const at = [p.lat_deg, p.lon_deg];
  const sigma = Number.isFinite(p.sigma_m) ? ` ±${num(p.sigma_m, 1)} m` : "";
  const text = p.source === "assumed" ? "assumed position (no fix)" : `believed${sigma}`;
  const out = [];
  if (sigma) out.push(L.circle(at, { radius: p.sigma_m, className: "chart-belief-ring", interactive: false }));
  const icon = L.divIcon({ className: `chart-belief source-${p.source}`, html: `<span>${text}</span>`, iconSize: [12, 12] });
  const marker = L.marker(at, { icon, keyboard: false, title: p.basis || text, interactive: false });
  marker.on("add", () => {
    const node = marker.getElement();
    if (node) Object.assign(node.dataset, { testid: "chart-belief", source: p.source, sigma: String(p.sigma_m ?? "") });
  });
  out.push(marker);
  return out;
}
