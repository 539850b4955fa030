// Telemetry over the dive (uPlot, served by the console from npm's copy): depth against the
// commanded depth (with a red bar along the surface where the vehicle's navigation was not
// valid), battery and speed, against seconds since the dive began. At page load the
// dive so far comes from the mission log (GET /api/series: a sample a second, on the dive's
// own clock), then live telemetry is appended, so a reload loses nothing and the axis starts
// at the dive's start. The samples are a bounded buffer that keeps the whole dive: when it is
// full every other sample goes and the sampling interval doubles. Redrawn at most once a
// second; emptied and loaded again on a new dive. With a fleet the plots are the selected
// vehicle's (the series of it, GET /api/series?vehicle=; the live telemetry app.js hands on
// is its alone), their titles naming it; emptied and loaded again when another is selected.

import { api } from "./api.js";
import { fleetKnown, selectedVehicle } from "./fleet.js";
import { $, el, on } from "./ui.js";

const UPLOT_JS = "/vendor/uplot/uPlot.esm.js";
const UPLOT_CSS = "/vendor/uplot/uPlot.min.css";
const MAX_POINTS = 3600;
const REDRAW_MS = 1000;
const HEIGHT_PX = 150;
const TICKS = 4; // about this many labelled ticks on each value axis

let uPlot = null;
const plots = [];
// t: the vehicle's clock (s); shown as t - t0, t0 the dive's start (its first sample)
const buf = { t: [], depth: [], commanded: [], navLost: [], battery: [], speed: [] };
const state = { t0: null, lastT: null, minDtS: 0.5, dirty: false, dive: undefined, samples: 0, loads: 0, logged: 0, vehicle: null };

/** The nav-lost bar's value: 0 (the surface line) where navigation was not valid, else null. */
export function navLost(navValid) {
  return navValid === false ? 0 : null;
}

/** The active command's commanded depth (m): its `depth`, or a helix's `end_depth`. */
export function commandedDepth(active) {
  const p = active && active.params;
  if (!p) return null;
  const d = p.depth !== undefined ? p.depth : p.end_depth;
  return Number.isFinite(d) ? d : null;
}

function reset() {
  for (const key of Object.keys(buf)) buf[key] = [];
  state.t0 = state.lastT = null;
  state.minDtS = 0.5;
  state.logged = 0;
  state.dirty = true;
}

function finite(v) {
  return Number.isFinite(v) ? v : null;
}

function halveIfFull() {
  while (buf.t.length >= MAX_POINTS) {
    for (const key of Object.keys(buf)) buf[key] = buf[key].filter((_, i) => i % 2 === 0);
    state.minDtS *= 2;
  }
}

function add(msg) {
  const status = msg && msg.status;
  const pose = msg && msg.pose;
  const t = finite(status && status.t_s) ?? finite(pose && pose.t_s);
  if (t === null) return;
  // /ws telemetry names its dive (GET /api/vehicle does not): another one starts the plots again
  if (msg.dive !== undefined && msg.dive !== state.dive) {
    if (state.dive !== undefined) reset();
    state.dive = msg.dive;
    loadSeries(); // the new dive's start, and what the log holds of it
  }
  // older than the last sample (a REST answer behind the websocket): not plotted
  if (state.lastT !== null && t - state.lastT < state.minDtS) return;
  if (state.t0 === null) state.t0 = t;
  state.lastT = t;
  const active = msg.active !== undefined ? msg.active : status && status.active;
  buf.t.push(t);
  buf.depth.push(finite(status && status.depth_m) ?? finite(pose && pose.z_m));
  buf.commanded.push(commandedDepth(active));
  buf.navLost.push(navLost(status && status.nav_valid));
  buf.battery.push(finite(status && status.battery_pct));
  buf.speed.push(finite(status && status.speed_mps));
  state.samples += 1;
  halveIfFull();
  state.dirty = true;
}

/** The dive so far from the mission log, before the live samples newer than its last (a
 *  fleet's: of the selected vehicle, once the page knows whether there is a fleet). */
async function loadSeries() {
  const load = ++state.loads;
  const fleet = await fleetKnown;
  if (load !== state.loads) return; // asked again meanwhile (another vehicle, another dive)
  const vehicle = fleet ? selectedVehicle() : null;
  const which = vehicle ? `&vehicle=${encodeURIComponent(vehicle)}` : "";
  let s;
  try {
    s = await api(`/api/series?limit=${MAX_POINTS}${which}`);
  } catch {
    return; // the live telemetry still plots from now on
  }
  if (load !== state.loads || !s || !Number.isFinite(s.start_t_s) || !Array.isArray(s.t_s)) return;
  if (state.dive !== undefined && s.dive !== state.dive) return; // another dive's: asked again
  if (state.dive === undefined) state.dive = s.dive;
  const start = s.start_t_s;
  const logged = s.t_s.map((t) => start + t);
  const last = logged.length ? logged[logged.length - 1] : -Infinity;
  // live samples of this dive the log does not hold yet (newer than its last sample)
  const live = buf.t.map((t, i) => i).filter((i) => buf.t[i] > last && buf.t[i] >= start);
  const navValid = Array.isArray(s.nav_valid) ? s.nav_valid : s.t_s.map(() => null);
  const cols = { depth: s.depth_m, commanded: s.commanded_depth_m, navLost: navValid.map(navLost), battery: s.battery_pct, speed: s.speed_mps };
  buf.t = [...logged, ...live.map((i) => buf.t[i])];
  for (const [key, values] of Object.entries(cols)) buf[key] = [...values, ...live.map((i) => buf[key][i])];
  state.t0 = start;
  state.lastT = buf.t.length ? buf.t[buf.t.length - 1] : null;
  state.logged = logged.length;
  if (Number.isFinite(s.interval_s)) state.minDtS = Math.max(state.minDtS, s.interval_s / 2);
  halveIfFull();
  state.dirty = true;
  redraw();
}

/** Another vehicle of the fleet selected: its samples, from its series, under its name. */
function selectVehicle(vehicle) {
  if (vehicle === state.vehicle) return;
  state.vehicle = vehicle;
  reset();
  retitle();
  $("plots").dataset.vehicle = vehicle;
  loadSeries();
}

/** A plot's title, naming the fleet's vehicle it shows ("Depth: auv2"). */
function titled(title) {
  return state.vehicle ? `${title}: ${state.vehicle}` : title;
}

function retitle() {
  for (const p of plots) {
    const node = p.root.querySelector(".u-title");
    if (node) node.textContent = titled(p.baseTitle);
  }
}

function redraw() {
  if (!state.dirty || !plots.length) return;
  state.dirty = false;
  const t0 = state.t0 ?? 0;
  const x = buf.t.map((t) => t - t0);
  plots[0].setData([x, buf.depth, buf.commanded, buf.navLost]);
  plots[1].setData([x, buf.battery]);
  plots[2].setData([x, buf.speed]);
  const box = $("plots");
  box.dataset.points = String(x.length);
  box.dataset.samples = String(state.samples);
  box.dataset.logged = String(state.logged);
}

// ---- readable axes: a range padded to round numbers, and a few round ticks in it ----

/** A round step (1, 2 or 5 x 10^k) giving about `count` steps across `span`. */
export function niceStep(span, count = TICKS) {
  const raw = span > 0 ? span / count : 1;
  const p = 10 ** Math.floor(Math.log10(raw));
  const m = raw / p;
  return (m <= 1 ? 1 : m <= 2 ? 2 : m <= 5 ? 5 : 10) * p;
}

/** [lo, hi] around the data, at least `minSpan` wide, ending on round steps, within
 *  [floor, ceiling] (a depth is not above the surface, a charge not over 100 %). */
export function niceRange(dataMin, dataMax, minSpan, floor = -Infinity, ceiling = Infinity) {
  let lo = Number.isFinite(dataMin) ? dataMin : 0;
  let hi = Number.isFinite(dataMax) ? dataMax : lo + minSpan;
  if (hi - lo < minSpan) {
    const mid = (lo + hi) / 2;
    [lo, hi] = [mid - minSpan / 2, mid + minSpan / 2];
  }
  const step = niceStep(hi - lo);
  lo = Math.max(floor, Math.floor(lo / step) * step);
  hi = Math.min(ceiling, Math.ceil(hi / step) * step);
  return hi > lo ? [lo, hi] : [lo, lo + step];
}

/** The round ticks in [min, max] (at least two: the ends when the step finds fewer). */
export function niceTicks(min, max) {
  if (!Number.isFinite(min) || !Number.isFinite(max) || max <= min) return [min];
  const step = niceStep(max - min);
  const digits = Math.max(0, -Math.floor(Math.log10(step)));
  const out = [];
  for (let v = Math.ceil(min / step - 1e-9) * step; v <= max + step * 1e-9; v += step) out.push(Number(v.toFixed(digits)));
  return out.length >= 2 ? out : [min, max];
}

/** The page's text colour (the theme's; a canvas cannot use CSS variables). */
const textColour = () => getComputedStyle($("plots")).color || "#888";

function axis(label, testid) {
  return {
    label,
    stroke: textColour,
    grid: { stroke: "rgba(128,128,128,0.25)", width: 1 },
    ticks: { stroke: "rgba(128,128,128,0.4)" },
    size: 48,
    splits: (u, i, min, max) => {
      const ticks = niceTicks(min, max);
      const box = u.box;
      if (box) box.dataset[testid] = JSON.stringify(ticks); // what is labelled (tests)
      return ticks;
    },
  };
}

function makePlot(host, title, testid, series, yLabel, scaleY) {
  const box = el("figure", { class: "plot", testid });
  host.append(box);
  const opts = {
    title: titled(title),
    width: 300,
    height: HEIGHT_PX,
    legend: { live: true },
    cursor: { drag: { x: false, y: false } },
    // the time axis starts at the dive's start (0), whatever the samples cover
    scales: { x: { time: false, range: (u, min, max) => niceRange(0, Math.max(10, max ?? 0), 10, 0) }, y: scaleY },
    axes: [{ ...axis("s since dive start", "xTicks"), size: 36 }, axis(yLabel, "yTicks")],
    series: [{ label: "t (s)" }, ...series],
  };
  const plot = new uPlot(opts, [[], ...series.map(() => [])], box);
  plot.box = box;
  plot.baseTitle = title;
  return plot;
}

function size() {
  const host = $("plots");
  const width = host.clientWidth;
  if (!width) return;
  const each = width >= 720 ? Math.floor(width / 3) - 12 : width - 8;
  for (const p of plots) p.setSize({ width: Math.max(200, each), height: HEIGHT_PX });
}

/** A value scale: at least `minSpan` wide, within [floor, ceiling]. */
function valueScale(minSpan, floor, ceiling = Infinity, extra = {}) {
  return { ...extra, range: (u, min, max) => niceRange(min, max, minSpan, floor, ceiling) };
}

/** Start the plots: listen to telemetry at once, load the dive from the log and uPlot, then
 *  draw once a second. */
export async function initPlots() {
  on("telemetry", ({ msg }) => add(msg));
  on("vehicle_selected", ({ vehicle }) => selectVehicle(vehicle)); // a fleet's (fleet.js)
  on("session", ({ session }) => {
    if (!session || session.dive === state.dive) return;
    if (state.dive !== undefined) reset(); // another dive (a reset, a console restarted)
    state.dive = session.dive;
    loadSeries();
  });
  loadSeries(); // at once: the session may come later
  const host = $("plots");
  // for the tests: the buffered samples as drawn (s since the dive's start)
  host.samplesShown = () => ({ t0: state.t0, t: buf.t.map((t) => t - (state.t0 ?? 0)), depth: [...buf.depth], battery: [...buf.battery], navLost: [...buf.navLost] });
  try {
    uPlot = (await import(UPLOT_JS)).default;
  } catch (err) {
    host.append(
      el(
        "p",
        { class: "viewer-missing", testid: "plots-missing" },
        "plots unavailable: the uPlot library is not installed on this console " +
          `(run \`make run\`, or \`npm ci --prefix frontend/vendor\`, with npm once): ${err.message}`,
      ),
    );
    return;
  }
  if (!document.querySelector(`link[href="${UPLOT_CSS}"]`)) document.head.append(el("link", { rel: "stylesheet", href: UPLOT_CSS }));
  plots.push(
    makePlot(
      host,
      "Depth",
      "plot-depth",
      [
        { label: "depth (m)", stroke: "#3fa7ff", width: 2 },
        { label: "commanded (m)", stroke: "#ffb13b", width: 1.5, dash: [6, 4] },
        { label: "nav lost", stroke: "#e5484d", width: 6, value: (u, v) => (v === null ? "" : "yes") },
      ],
      "m (down)",
      valueScale(2, 0, Infinity, { dir: -1 }), // depth grows downwards, as in the water
    ),
    makePlot(host, "Battery", "plot-battery", [{ label: "battery (%)", stroke: "#49c26e", width: 2 }], "%", valueScale(5, 0, 100)),
    makePlot(host, "Speed", "plot-speed", [{ label: "speed (m/s)", stroke: "#c78bff", width: 2 }], "m/s", valueScale(0.2, 0)),
  );
  host.classList.add("plots-ready");
  size();
  new ResizeObserver(size).observe(host);
  // the axes' colour follows the theme (day / night)
  new MutationObserver(() => plots.forEach((p) => p.redraw(false, true))).observe(document.documentElement, { attributes: true, attributeFilter: ["data-theme", "class"] });
  state.dirty = true;
  redraw();
  setInterval(redraw, REDRAW_MS);
}
