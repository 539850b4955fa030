// Every vehicle of a fleet on the chart (issue 23): a marker where the console believes it is
// (its belief's lat/lon: none without a datum), labelled with its name, its address and the
// command it is believed to run with p; hover for the position's basis. chart.js keeps the
// selected vehicle's own layers (its fix and heading, its track, its active path, its belief
// ring). Without a fleet nothing is drawn here.

import { candidateText } from "./belief.js";
import { pct } from "./delivery.js";
import { addressOf, selectedVehicle } from "./fleet.js";
import { el, num, on } from "./ui.js";

let L = null;
let layer = null;
const beliefs = new Map(); // name -> the newest belief (fleet-rows.js keeps the newest)
const markers = new Map(); // name -> Leaflet marker

export function initFleetChart() {
  on("chart_ready", ({ leaflet, map }) => {
    L = leaflet;
    layer = L.layerGroup().addTo(map);
    for (const name of beliefs.keys()) draw(name);
  });
  on("fleet_belief", ({ belief }) => {
    beliefs.set(belief.vehicle, belief);
    draw(belief.vehicle);
  });
  on("vehicle_selected", () => {
    for (const name of beliefs.keys()) draw(name);
  });
}

/** The label, two short lines: "auv2 · 2" and "circle p 99.99 %" (the command in full on hover). */
function label(name, b) {
  const address = addressOf(name);
  const c = b.command;
  const what = !c ? "" : c.kind === "unknown" ? "unknown" : c.pattern || "holding";
  return el("span", { class: "chart-fleet-label" },
    el("strong", {}, name), address === null ? "" : ` · ${address}`,
    c ? el("span", { class: "chart-fleet-command" }, `${what} p ${pct(c.p)}`) : null);
}

function basisText(p) {
  const sigma = Number.isFinite(p.sigma_m) && p.source !== "telemetry" ? ` ± ${num(p.sigma_m, 1)} m` : "";
  const how = p.source === "telemetry" ? "the last fix" : p.source === "dead_reckoning" ? "dead-reckoned" : "assumed";
  return `x ${num(p.x_m, 1)} m N, y ${num(p.y_m, 1)} m E, depth ${num(p.z_m, 1)} m (${how}${sigma}): ${p.basis || ""}`;
}

function draw(name) {
  if (!layer) return;
  const b = beliefs.get(name);
  const p = b && b.position;
  const old = markers.get(name);
  if (!p || !Number.isFinite(p.lat_deg) || !Number.isFinite(p.lon_deg)) {
    if (old) layer.removeLayer(old);
    markers.delete(name);
    return;
  }
  const at = [p.lat_deg, p.lon_deg];
  const selected = name === selectedVehicle();
  const icon = L.divIcon({
    className: `chart-fleet source-${p.source}${selected ? " selected" : ""}`,
    html: label(name, b),
    iconSize: [12, 12],
  });
  const marker = old || L.marker(at, { icon, keyboard: false, zIndexOffset: selected ? 900 : 800 });
  if (old) {
    marker.setLatLng(at);
    marker.setIcon(icon);
    marker.setZIndexOffset(selected ? 900 : 800);
  } else {
    markers.set(name, marker);
    layer.addLayer(marker);
  }
  const node = marker.getElement();
  if (node) {
    const c = b.command;
    node.title = `${name}: ${c ? `${candidateText(c, b.two_way)} (p ${pct(c.p)}); ` : ""}${basisText(p)}`;
    Object.assign(node.dataset, { testid: `chart-fleet-${name}`, vehicle: name, lat: String(p.lat_deg), lon: String(p.lon_deg), source: p.source });
  }
}
