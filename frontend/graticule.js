// The chart's latitude/longitude graticule: lines every N minutes (N chosen from the view so
// that a few lines cross it), labelled in degrees and decimal minutes as on a paper chart
// (29°31.896'N, 082°18.186'W: the same form as backend/chart/geo.py's dm()). Drawn always, with or
// without map tiles. In Web Mercator parallels and meridians are straight lines, so each
// line is exact with two points.

/** Line spacings (minutes of arc) to choose from, finest first: 1.85 m ... 30°. */
const STEPS_MIN = [
  0.001, 0.002, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1, 2, 5, 10, 15, 30, 60, 120, 300, 600, 900, 1800,
];
const LABEL_W_PX = 110; // room a longitude label needs across
const LABEL_H_PX = 36; // room a latitude label needs down

/** Degrees and decimal minutes, as on a chart: 29°31.896'N, 082°18.186'W. */
export function dm(valueDeg, lat) {
  const hemi = lat ? (valueDeg >= 0 ? "N" : "S") : valueDeg >= 0 ? "E" : "W";
  const a = Math.abs(valueDeg);
  let deg = Math.floor(a);
  let minutes = (a - deg) * 60;
  if (Number((minutes).toFixed(3)) >= 60) {
    deg += 1;
    minutes = 0;
  }
  return `${String(deg).padStart(lat ? 2 : 3, "0")}°${minutes.toFixed(3).padStart(6, "0")}'${hemi}`;
}

/** The finest spacing (min) that puts at most `maxLines` lines across `spanDeg`. */
export function stepMinutes(spanDeg, maxLines) {
  const spanMin = Math.abs(spanDeg) * 60;
  for (const step of STEPS_MIN) if (spanMin / step <= maxLines) return step;
  return STEPS_MIN[STEPS_MIN.length - 1];
}

/** Values k*step (deg) inside [lo, hi]; integer k keeps them exact. */
function ticks(loDeg, hiDeg, stepMin) {
  const out = [];
  const k0 = Math.ceil((loDeg * 60) / stepMin);
  const k1 = Math.floor((hiDeg * 60) / stepMin);
  for (let k = k0; k <= k1 && out.length < 200; k++) out.push((k * stepMin) / 60);
  return out;
}

/**
 * Draw the graticule of `map`'s view into `group` (a Leaflet LayerGroup, emptied first).
 * `L` is the Leaflet module. Lines go to the "graticule" pane, labels to "graticule-labels".
 */
export function drawGraticule(L, map, group) {
  group.clearLayers();
  const size = map.getSize();
  if (!size.x || !size.y) return;
  const b = map.getBounds();
  const south = Math.max(b.getSouth(), -85);
  const north = Math.min(b.getNorth(), 85);
  const west = b.getWest();
  const east = b.getEast();
  const latStep = stepMinutes(north - south, Math.max(2, Math.floor(size.y / LABEL_H_PX)));
  const lonStep = stepMinutes(east - west, Math.max(2, Math.floor(size.x / LABEL_W_PX)));
  const line = { pane: "graticule", className: "graticule-line", interactive: false, weight: 1 };
  const label = (text, cls, anchor) =>
    L.divIcon({ className: `graticule-label ${cls}`, html: text, iconSize: null, iconAnchor: anchor });
  for (const lat of ticks(south, north, latStep)) {
    group.addLayer(L.polyline([[lat, west], [lat, east]], line));
    // not under the longitude labels' row at the top
    if (map.latLngToContainerPoint([lat, west]).y < 18) continue;
    group.addLayer(
      L.marker([lat, west], { pane: "graticule-labels", interactive: false, keyboard: false, icon: label(dm(lat, true), "graticule-lat", [-3, 15]) }),
    );
  }
  for (const lon of ticks(west, east, lonStep)) {
    group.addLayer(L.polyline([[south, lon], [north, lon]], line));
    // not under the zoom and view buttons at the top right
    if (map.latLngToContainerPoint([north, lon]).x > size.x - LABEL_W_PX + 10) continue;
    group.addLayer(
      L.marker([north, lon], { pane: "graticule-labels", interactive: false, keyboard: false, icon: label(dm(lon, false), "graticule-lon", [-3, -3]) }),
    );
  }
  group.stepMinutes = { lat: latStep, lon: lonStep };
}
