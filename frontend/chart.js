// The 2D chart (Leaflet, served by the console from npm's copy: no CDN, no request leaves the
// machine): the graticule, optional local tiles, the transmitter and its ME range rings, the
// vehicle and its track, the active path, this page's preview shaded by the link's reach, and
// the predicted track (prediction.js). Positions come from the API's lat_deg/lon_deg; the
// page never converts NED metres itself (backend/chart/geo.py is the one edge).

import { api } from "./api.js";
import { beliefLayers } from "./belief.js";
import { buttonsControl, fitPadding, legendControl } from "./chart-controls.js";
import { watchOperator } from "./chart-operator.js";
import { vehicleQuery } from "./fleet.js";
import { fleetLatLngs } from "./fleet-chart.js";
import { drawGraticule } from "./graticule.js";
import { $, el, emit, on, num } from "./ui.js";

const LEAFLET_JS = "/vendor/leaflet/leaflet-src.esm.js";
const LEAFLET_CSS = "/vendor/leaflet/leaflet.css";
const MAX_ZOOM = 22; // ~4 cm a pixel: a 5 m circle still reads
const FIT_MAX_ZOOM = 20;
const TRACK_POINTS = 3600;
const TRACK_MIN_DEG = 2e-6; // ~0.2 m: closer fixes are not added to the track
const CHART_REFRESH_MS = 30000; // the station moves with a surface GPS

let L = null;
let map = null;
const layers = {};
const state = {
  chart: null, // GET /api/chart
  preview: null,
  predicted: null,
  pose: null,
  heading: null, // deg from north
  trackDrawnAt: 0, // performance.now() of the last track redraw
  dive: null,
  lastT: null,
  track: [],
  active: null, // the vehicle's echoed active command
  activePath: null, // the console's mirror of the path the vehicle flies (/api/vehicle, /ws)
  previewed: new Map(), // command key -> preview path latlngs (the active path, as previewed)
  belief: null, // the console's belief (belief.js): its position is drawn unless it is the fix
  fittedRing: false,
  fittedPath: false,
  operatorMoved: false, // dragged or zoomed by the operator: new previews no longer refit it
};

function missing(text) {
  const node = $("chart-missing");
  node.textContent = text;
  node.hidden = !text;
}

function addCss(href) {
  if (document.querySelector(`link[href="${href}"]`)) return;
  document.head.append(el("link", { rel: "stylesheet", href }));
}

/** [[lat, lon], ...] of an object's lat_deg/lon_deg lists (null when there are none). */
export function latLngs(obj) {
  const lat = obj && obj.lat_deg;
  const lon = obj && obj.lon_deg;
  if (!Array.isArray(lat) || !Array.isArray(lon) || !lat.length) return null;
  const out = [];
  for (let i = 0; i < lat.length; i++) {
    if (Number.isFinite(lat[i]) && Number.isFinite(lon[i])) out.push([lat[i], lon[i]]);
  }
  return out.length ? out : null;
}

function commandKey(cmd) {
  if (!cmd || !cmd.pattern) return null;
  const params = Object.entries(cmd.params || {})
    .sort(([a], [b]) => a.localeCompare(b))
    .map(([k, v]) => `${k}=${typeof v === "number" ? Number(v.toFixed(6)) : v}`);
  return `${cmd.pattern}:${params.join(",")}`;
}

// ---- controls ----

function centreOnVehicle() {
  state.operatorMoved = true; // the operator chose this view
  if (state.pose) map.setView(state.pose, Math.max(map.getZoom(), 17));
}

/** The Fit button: fit now, and fit each new preview again from now on. */
function fitButton() {
  state.operatorMoved = false;
  $("chart").dataset.fit = "auto";
  fitAll();
}

/** Fit the preview, the vehicle (a fleet: every vehicle) and (`predicted`) the predicted
 *  track: a new preview's own fit leaves out the track predicted for the command before it. */
function fitAll(predicted = true) {
  $("chart").dataset.fits = String(Number($("chart").dataset.fits || 0) + 1); // (tests)
  const pts = [...(latLngs(state.preview && state.preview.path) || []), ...((predicted && state.predicted) || [])];
  if (state.pose) pts.push(state.pose);
  pts.push(...fleetLatLngs()); // none without a fleet
  if (pts.length) map.fitBounds(L.latLngBounds(pts), { ...fitPadding($("chart")), maxZoom: FIT_MAX_ZOOM });
  else if (layers.ring) map.fitBounds(layers.ring.getBounds(), { padding: [8, 8] });
}

// ---- drawing ----

function drawStation() {
  layers.station.clearLayers();
  const c = state.chart;
  const s = c && c.station;
  if (!s || !Number.isFinite(s.lat_deg) || !Number.isFinite(s.lon_deg)) return;
  const at = [s.lat_deg, s.lon_deg];
  const range = Number(c.me_range_m);
  const fraction = Number.isFinite(c.marginal_fraction) ? c.marginal_fraction : 0.75;
  if (range > 0) {
    layers.ring = L.circle(at, { radius: range, className: "chart-range-ring", interactive: false, fill: false });
    layers.station.addLayer(layers.ring);
    layers.station.addLayer(L.circle(at, { radius: range * fraction, className: "chart-marginal-ring", interactive: false, fill: false }));
  }
  const tip = `transmitter (${s.source || "station"})${range > 0 ? `, ME range ${num(range, 0)} m` : ""}`;
  layers.station.addLayer(
    L.marker(at, { title: tip, keyboard: false, icon: L.divIcon({ className: "chart-station", html: "", iconSize: [14, 14] }) }),
  );
  if (!state.fittedRing && layers.ring && !state.fittedPath) {
    state.fittedRing = true;
    map.fitBounds(layers.ring.getBounds(), { padding: [8, 8] });
  }
}

function drawTiles() {
  if (layers.tiles) layers.tiles.remove();
  layers.tiles = null;
  const t = state.chart && state.chart.tiles;
  if (!t || !t.url) return;
  // below the tiles' shallowest zoom the layer is hidden, not drawn from deeper tiles (that
  // would ask for thousands of them); above their deepest, their deepest are enlarged
  layers.tiles = L.tileLayer(t.url, {
    minZoom: Number.isInteger(t.min_zoom) ? t.min_zoom : 0,
    maxNativeZoom: Number.isInteger(t.max_zoom) ? t.max_zoom : undefined,
    maxZoom: MAX_ZOOM,
    className: "chart-tiles",
    attribution: "",
  }).addTo(map);
}

function drawPreview() {
  layers.preview.clearLayers();
  const p = state.preview;
  const pts = latLngs(p && p.path);
  const warning = $("reach-warning");
  const reach = p && p.link_reach;
  warning.textContent = (reach && reach.warning) || "";
  warning.hidden = !(reach && reach.warning);
  if (!pts) return;
  // each new preview is fitted, unless the operator has moved or zoomed the chart since
  if (!state.operatorMoved) {
    state.fittedPath = true;
    fitAll(false);
  }
  const segments = reach && Array.isArray(reach.segments) && reach.segments.length ? reach.segments : [{ state: null, start: 0, end: pts.length - 1 }];
  for (const seg of segments) {
    // from the waypoint before: the stretch into a segment is drawn in the segment's state
    const part = pts.slice(Math.max(0, seg.start - 1), Math.min(pts.length, seg.end + 1));
    if (!part.length) continue;
    const cls = `chart-preview${seg.state ? ` reach-${seg.state}` : ""}`;
    const line = L.polyline(part, { className: cls, interactive: false });
    layers.preview.addLayer(line);
  }
}

function drawPredicted() {
  layers.predicted.clearLayers();
  if (state.predicted && state.predicted.length > 1) {
    layers.predicted.addLayer(L.polyline(state.predicted, { className: "chart-predicted", interactive: false, dashArray: "6 6" }));
  }
}

function drawActive() {
  layers.active.clearLayers();
  // the console's mirror of the path the vehicle flies; else this page's own preview of it
  const key = commandKey(state.active);
  const pts = latLngs(state.activePath) || (key && state.previewed.get(key));
  if (pts && pts.length > 1) layers.active.addLayer(L.polyline(pts, { className: "chart-active", interactive: false }));
}

function drawVehicle() {
  if (!state.pose) return;
  const heading = state.heading;
  if (!layers.vehicle) {
    const icon = L.divIcon({
      className: "chart-vehicle",
      html: '<svg viewBox="-10 -10 20 20" width="22" height="22" aria-hidden="true"><path d="M0,-9 L6,7 L0,3 L-6,7 Z"/></svg>',
      iconSize: [22, 22],
    });
    layers.vehicle = L.marker(state.pose, { icon, keyboard: false, title: "vehicle", zIndexOffset: 1000 }).addTo(map);
  } else {
    layers.vehicle.setLatLng(state.pose);
  }
  const node = layers.vehicle.getElement();
  const svg = node && node.querySelector("svg");
  if (svg && Number.isFinite(heading)) svg.style.transform = `rotate(${heading}deg)`;
  if (node) {
    node.dataset.heading = Number.isFinite(heading) ? String(heading) : "";
    [node.dataset.lat, node.dataset.lon] = state.pose.map(String);
  }
  // the track (up to TRACK_POINTS) at most once a second: telemetry comes at up to 10 Hz
  const now = performance.now();
  if (now - state.trackDrawnAt >= 1000) {
    state.trackDrawnAt = now;
    layers.track.setLatLngs(state.track);
  }
}

/** The believed position when it is not the last fix (belief.js draws it). */
function drawBelief() {
  layers.belief.clearLayers();
  for (const layer of beliefLayers(L, state.belief)) layers.belief.addLayer(layer);
}

function resetTrack() {
  state.track = [];
  if (layers.track) layers.track.setLatLngs([]);
}

// ---- inputs ----

function onActivePath(path) {
  state.activePath = path || null;
  if (map) drawActive();
}

function onTelemetry(msg) {
  if (msg && msg.active_path !== undefined) onActivePath(msg.active_path);
  const pose = msg && msg.pose;
  const active = msg && (msg.active !== undefined ? msg.active : msg.status && msg.status.active);
  if (active !== undefined) onActive(active);
  if (!pose) return;
  if (Number.isFinite(pose.t_s)) {
    if (state.lastT !== null && pose.t_s < state.lastT - 1) resetTrack(); // a new dive (reset)
    state.lastT = pose.t_s;
  }
  if (!Number.isFinite(pose.lat_deg) || !Number.isFinite(pose.lon_deg)) return;
  state.pose = [pose.lat_deg, pose.lon_deg];
  state.heading = Number.isFinite(pose.heading_deg) ? pose.heading_deg : null;
  const last = state.track[state.track.length - 1];
  if (!last || Math.abs(last[0] - pose.lat_deg) > TRACK_MIN_DEG || Math.abs(last[1] - pose.lon_deg) > TRACK_MIN_DEG) {
    state.track.push(state.pose);
    if (state.track.length > TRACK_POINTS) state.track.splice(0, state.track.length - TRACK_POINTS);
  }
  if (map) drawVehicle();
}

function onActive(active) {
  if (commandKey(active) === commandKey(state.active)) return;
  state.active = active || null;
  if (map) drawActive();
}

function onPreview(detail) {
  state.preview = detail.preview;
  const pts = latLngs(detail.preview && detail.preview.path);
  const key = commandKey(detail.preview);
  if (pts && key) {
    state.previewed.delete(key);
    state.previewed.set(key, pts);
    while (state.previewed.size > 50) state.previewed.delete(state.previewed.keys().next().value);
  }
  if (map) {
    drawPreview();
    drawActive();
  }
}

async function loadChart() {
  let chart = null;
  try {
    chart = await api("/api/chart");
  } catch (err) {
    missing(`no chart reference: /api/chart failed (${err.message})`);
    return;
  }
  state.chart = chart;
  missing(
    chart && !chart.datum
      ? "no geo reference (datum): set datum_lat_deg and datum_lon_deg, or a surface GPS; positions are in metres only"
      : "",
  );
  if (!map) return;
  drawStation(); // first: it may set the first view
  const tilesUrl = chart && chart.tiles && chart.tiles.url;
  if ((layers.tiles ? layers.tiles._url : undefined) !== tilesUrl) drawTiles();
}

/** The dive's track so far (the log keeps it at 1 Hz), before what telemetry adds. */
async function loadTrack(dive) {
  if (!Number.isInteger(dive)) return;
  let doc;
  const query = vehicleQuery(); // a fleet: the selected vehicle's
  try {
    doc = await api(`/api/dives/${dive}${query}`);
  } catch {
    return; // telemetry still draws the track from now on
  }
  if (dive !== state.dive || query !== vehicleQuery() || !doc || !Array.isArray(doc.track)) return;
  const old = doc.track
    .filter((p) => Number.isFinite(p.lat_deg) && Number.isFinite(p.lon_deg))
    .map((p) => [p.lat_deg, p.lon_deg]);
  state.track = [...old, ...state.track].slice(-TRACK_POINTS);
  state.trackDrawnAt = 0;
  if (map) drawVehicle();
}

/** Draw the predicted track ([[lat, lon], ...] or null: none). */
export function showPredicted(latlngs) {
  state.predicted = latlngs && latlngs.length ? latlngs : null;
  if (map) drawPredicted();
}

function createMap() {
  map = L.map($("chart"), {
    crs: L.CRS.EPSG3857,
    attributionControl: false, // its default prefix links out
    zoomControl: false,
    maxZoom: MAX_ZOOM,
    minZoom: 2,
    zoomSnap: 0.5,
    worldCopyJump: false,
  });
  map.setView([0, 0], 2);
  L.control.zoom({ position: "topright" }).addTo(map);
  buttonsControl(L, { centre: centreOnVehicle, fit: fitButton }).addTo(map);
  legendControl(L).addTo(map);
  watchOperator(map, () => {
    state.operatorMoved = true;
    $("chart").dataset.fit = "operator";
  });
  for (const [name, z] of [["graticule", 250], ["graticule-labels", 450]]) {
    const pane = map.createPane(name);
    pane.style.zIndex = String(z);
    pane.style.pointerEvents = "none";
  }
  layers.graticule = L.layerGroup().addTo(map);
  layers.station = L.layerGroup().addTo(map);
  layers.track = L.polyline([], { className: "chart-track", interactive: false }).addTo(map);
  layers.active = L.layerGroup().addTo(map);
  layers.preview = L.layerGroup().addTo(map);
  layers.predicted = L.layerGroup().addTo(map);
  layers.belief = L.layerGroup().addTo(map);
  const redrawGrid = () => drawGraticule(L, map, layers.graticule);
  map.on("moveend zoomend resize", redrawGrid);
  redrawGrid();
  new ResizeObserver(() => map.invalidateSize()).observe($("chart"));
}

/** Start the chart: listen to the page's events at once, load Leaflet, then draw. */
export async function initChart() {
  on("telemetry", ({ msg }) => onTelemetry(msg));
  on("vehicle", ({ msg }) => msg && onActive(msg.active));
  on("active_path", ({ path }) => onActivePath(path));
  on("preview", onPreview);
  on("fleet_marker_added", () => { // a fleet: a vehicle newly on the chart is fitted in too
    if (map && state.fittedPath && !state.operatorMoved) fitAll(false);
  });
  on("belief", ({ belief }) => {
    state.belief = belief;
    if (map) drawBelief();
  });
  on("vehicle_selected", () => { // a fleet: this chart's own vehicle layers follow the selection
    resetTrack();
    Object.assign(state, { pose: null, heading: null, lastT: null, active: null, activePath: null, belief: null });
    if (layers.vehicle) layers.vehicle.remove();
    layers.vehicle = null;
    if (map) {
      drawActive();
      drawBelief();
    }
    loadTrack(state.dive);
  });
  on("session", ({ session }) => {
    if (!session || session.dive === state.dive) return;
    if (state.dive !== null) resetTrack();
    state.dive = session.dive;
    loadTrack(session.dive);
  });
  try {
    L = await import(LEAFLET_JS);
  } catch (err) {
    missing(
      "chart unavailable: the Leaflet library is not installed on this console " +
        `(run \`make run\`, or \`npm ci --prefix frontend/vendor\`, with npm once): ${err.message}`,
    );
    $("chart-panel").classList.add("chart-unavailable");
    return;
  }
  addCss(LEAFLET_CSS);
  createMap();
  emit("chart_ready", { leaflet: L, map }); // a fleet's markers (fleet-chart.js)
  $("chart-panel").classList.add("chart-ready");
  await loadChart();
  drawPreview();
  drawPredicted();
  drawActive();
  drawVehicle();
  drawBelief();
  setInterval(loadChart, CHART_REFRESH_MS);
}
