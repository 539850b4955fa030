// Every vehicle of a fleet on the chart (issue 23): a marker where the console believes it is
// (its belief's lat/lon: none without a datum), labelled with its name, its address and the
// command it is believed to run with p; hover for the position's basis. chart.js keeps the
// selected vehicle's own layers (its fix and heading, its track, its active path, its belief
// ring). Without a fleet nothing is drawn here. The chart's fit takes every marker's position
// (fleetLatLngs), and a label near the chart's edge (or another label, or the chart's buttons)
// goes to a side of its dot with room (placeLabels), so none is cut by the edge.

import { candidateText } from "./belief.js";
import { pct } from "./delivery.js";
import { addressOf, selectedVehicle } from "./fleet.js";
import { el, emit, num, on } from "./ui.js";

let L = null;
let map = null;
let layer = null;
const beliefs = new Map(); // name -> the newest belief (fleet-rows.js keeps the newest)
const markers = new Map(); // name -> Leaflet marker

export function initFleetChart() {
  on("chart_ready", ({ leaflet, map: chart }) => {
    L = leaflet;
    map = chart;
    layer = L.layerGroup().addTo(map);
    // every step of a move, a zoom or a resize (the page's layout) places them again
    map.on("move zoom moveend zoomend viewreset resize", placeSoon);
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

/** [[lat, lon], ...] of every vehicle's marker (where the console believes it is): the
 *  chart's fit takes them all, not only the selected vehicle's. */
export function fleetLatLngs() {
  return [...markers.values()].map((m) => {
    const at = m.getLatLng();
    return [at.lat, at.lng];
  });
}

let placing = 0; // the animation frame a placement is due in (0: none)

/** Place the labels in the next animation frame (once, however many calls before it): where
 *  the map's panes, markers and the page's layout are as they will be drawn. */
function placeSoon() {
  if (!placing) placing = requestAnimationFrame(placeLabels);
}

/** Each marker's label where the chart's box holds it whole, clear of the chart's buttons and
 *  legend, the vehicles' dots and the labels placed before it: right of its dot, else left,
 *  else (right, then left) below or above it; then moved down or up where the top or bottom
 *  edge would still cut it. West first, so the eastern ones make way at the right edge.
 *  Measured, not computed from fleet.css's offsets. Run (placeSoon) after each draw and
 *  each step of a move. */
export function placeLabels() {
  placing = 0;
  if (!map) return;
  const box = map.getContainer().getBoundingClientRect();
  const labels = [];
  const taken = [...map.getContainer().querySelectorAll(".leaflet-control")].map(bounds);
  for (const marker of markers.values()) {
    const node = marker.getElement();
    const text = node && node.querySelector(".chart-fleet-label");
    if (!text) continue;
    text.classList.remove("flip");
    text.style.top = "";
    taken.push(bounds(node));
    labels.push({ text, x: map.latLngToContainerPoint(marker.getLatLng()).x });
  }
  const inside = (r) => r.left >= box.left && r.right <= box.right && r.top >= box.top && r.bottom <= box.bottom;
  const clear = (r) => !taken.some((t) => r.left < t.right && t.left < r.right && r.top < t.bottom && t.top < r.bottom);
  labels.sort((a, b) => a.x - b.x);
  for (const { text } of labels) {
    const right = bounds(text);
    text.classList.add("flip");
    const left = bounds(text);
    const h = right.bottom - right.top;
    const options = [];
    for (const dy of [0, h, -h]) {
      for (const [flip, r] of [[false, right], [true, left]]) options.push({ flip, dy, r: shifted(r, dy) });
    }
    const best = options.find((o) => inside(o.r) && clear(o.r)) || options.find((o) => inside(o.r)) || options[0];
    text.classList.toggle("flip", best.flip);
    const edge = best.r.top < box.top ? box.top - best.r.top : best.r.bottom > box.bottom ? box.bottom - best.r.bottom : 0;
    if (best.dy + edge) text.style.top = `${parseFloat(getComputedStyle(text).top) + best.dy + edge}px`;
    taken.push(shifted(best.r, edge));
  }
}

function bounds(node) {
  const r = node.getBoundingClientRect();
  return { left: r.left, right: r.right, top: r.top, bottom: r.bottom };
}

function shifted(r, dy) {
  return { ...r, top: r.top + dy, bottom: r.bottom + dy };
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
  placeLabels(); // its new label at once (no frame with it unplaced)
  if (!old) emit("fleet_marker_added", { name }); // the chart fits it in (chart.js)
}
