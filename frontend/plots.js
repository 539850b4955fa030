// Telemetry over the dive (uPlot, served by the console from npm's copy): depth against the
// commanded depth, battery and speed, against seconds since the dive began. The samples are
// a bounded buffer that keeps the whole dive: when it is full every other sample goes and the
// sampling interval doubles. Redrawn at most once a second; emptied on a new dive.

import { $, el, on } from "./ui.js";

const UPLOT_JS = "/vendor/uplot/uPlot.esm.js";
const UPLOT_CSS = "/vendor/uplot/uPlot.min.css";
const MAX_POINTS = 3600;
const REDRAW_MS = 1000;
const HEIGHT_PX = 120;

let uPlot = null;
const plots = [];
const buf = { t: [], depth: [], commanded: [], battery: [], speed: [] };
const state = { t0: null, lastT: null, minDtS: 0.5, dirty: false, dive: null, samples: 0 };

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
  state.dirty = true;
}

function finite(v) {
  return Number.isFinite(v) ? v : null;
}

function add(msg) {
  const status = msg && msg.status;
  const pose = msg && msg.pose;
  const t = finite(status && status.t_s) ?? finite(pose && pose.t_s);
  if (t === null) return;
  if (state.lastT !== null && t < state.lastT - 1) reset(); // the vehicle's clock restarted: a new dive
  if (state.lastT !== null && t - state.lastT < state.minDtS) return;
  if (state.t0 === null) state.t0 = t;
  state.lastT = t;
  const active = msg.active !== undefined ? msg.active : status && status.active;
  buf.t.push(t - state.t0);
  buf.depth.push(finite(status && status.depth_m) ?? finite(pose && pose.z_m));
  buf.commanded.push(commandedDepth(active));
  buf.battery.push(finite(status && status.battery_pct));
  buf.speed.push(finite(status && status.speed_mps));
  state.samples += 1;
  if (buf.t.length >= MAX_POINTS) {
    for (const key of Object.keys(buf)) buf[key] = buf[key].filter((_, i) => i % 2 === 0);
    state.minDtS *= 2;
  }
  state.dirty = true;
}

function redraw() {
  if (!state.dirty || !plots.length) return;
  state.dirty = false;
  const x = buf.t;
  plots[0].setData([x, buf.depth, buf.commanded]);
  plots[1].setData([x, buf.battery]);
  plots[2].setData([x, buf.speed]);
  const box = $("plots");
  box.dataset.points = String(x.length);
  box.dataset.samples = String(state.samples);
}

/** The page's text colour (the theme's; a canvas cannot use CSS variables). */
const textColour = () => getComputedStyle($("plots")).color || "#888";

function axis(label) {
  return { label, stroke: textColour, grid: { stroke: "rgba(128,128,128,0.25)", width: 1 }, ticks: { stroke: "rgba(128,128,128,0.4)" }, size: 44 };
}

function makePlot(host, title, testid, series, yLabel, scaleY = {}) {
  const box = el("figure", { class: "plot", testid });
  host.append(box);
  const opts = {
    title,
    width: 300,
    height: HEIGHT_PX,
    legend: { live: true },
    cursor: { drag: { x: false, y: false } },
    scales: { x: { time: false }, y: scaleY },
    axes: [{ ...axis("s since dive start"), size: 36 }, axis(yLabel)],
    series: [{ label: "t (s)" }, ...series],
  };
  const plot = new uPlot(opts, [[], ...series.map(() => [])], box);
  plot.box = box;
  return plot;
}

function size() {
  const host = $("plots");
  const width = host.clientWidth;
  if (!width) return;
  const each = width >= 720 ? Math.floor(width / 3) - 12 : width - 8;
  for (const p of plots) p.setSize({ width: Math.max(200, each), height: HEIGHT_PX });
}

/** Start the plots: listen to telemetry at once, load uPlot, then draw once a second. */
export async function initPlots() {
  on("telemetry", ({ msg }) => add(msg));
  on("session", ({ session }) => {
    if (session && state.dive !== null && session.dive !== state.dive) reset();
    if (session) state.dive = session.dive;
  });
  const host = $("plots");
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
      ],
      "m (down)",
      { dir: -1 }, // depth grows downwards, as in the water
    ),
    makePlot(host, "Battery", "plot-battery", [{ label: "battery (%)", stroke: "#49c26e", width: 2 }], "%"),
    makePlot(host, "Speed", "plot-speed", [{ label: "speed (m/s)", stroke: "#c78bff", width: 2 }], "m/s"),
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
