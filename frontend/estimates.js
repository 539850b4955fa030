// The estimate's rows (length, duration, battery use, depth range, the join), as the preview
// panel shows them and as the confirm dialog repeats them: a repeating pattern's duration as its
// one lap, and why the estimate and the plan's own clock differ when they do.

import { $, el, num, withUnit } from "./ui.js";
import { duration } from "./prediction.js";

/** A repeating pattern has no end, so no total duration: its one lap instead. */
function durationText(e) {
  if (!e.repeats) return duration(e.duration_s);
  const lap = Number(e.lap_duration_s);
  return `repeats until retasked (one lap ${Number.isFinite(lap) ? Math.round(lap).toLocaleString("en-US") : "unknown"} s)`;
}

/** One estimate row; for a repeating pattern the duration spans the row, and the length and
 *  battery use say on hover that they are the join and one lap. The duration is labelled as
 *  what it is: estimated (as the vehicle's profile flies the plan). */
function estimateRow(e, key, value) {
  const lap = e.repeats && (key === "length" || key === "battery use");
  const wide = e.repeats && key === "duration";
  const label = key === "duration" ? "estimated duration" : key;
  return el("div", { dataset: { key }, class: wide ? "wide" : null, title: lap ? "the join and one lap" : null },
    el("dt", {}, label), el("dd", {}, value));
}

/** The estimate's rows, and right after its duration why it and the plan's own clock differ
 *  (by more than 20 %), when they do. */
function estimateRows(e, rows) {
  const out = [];
  for (const [key, value] of rows) {
    out.push(estimateRow(e, key, value));
    const notes = Array.isArray(e.duration_notes) ? e.duration_notes : [];
    if (key === "duration" && notes.length) {
      const title = `the plan's own clock says ${duration(e.planned_duration_s)}`;
      out.push(el("div", { dataset: { key: "why" }, class: "wide", title, testid: "estimate-notes" },
        el("dt", {}, "why"), el("dd", {}, notes.join("; "))));
    }
  }
  return out;
}

/** The preview panel's estimates (none: says so). */
export function renderEstimates(e) {
  const box = $("estimates");
  if (!e) {
    box.replaceChildren(el("div", {}, el("dt", {}, "–"), el("dd", {}, "no estimate")));
    return;
  }
  const depth = e.depth_min_m == null ? "–" : `${num(e.depth_min_m, 2)} to ${num(e.depth_max_m, 2)} m`;
  const rows = [
    ["length", withUnit(e.length_m, "m", 1)],
    ["duration", durationText(e)],
    ["battery use", withUnit(e.battery_pct, "%", 2)],
    ["depth range", depth],
    ["join", `${withUnit(e.join_length_m, "m", 1)}, ${duration(e.join_duration_s)}`],
  ];
  box.replaceChildren(...estimateRows(e, rows));
}

/** What the new plan costs: shown on every send, the first one too. */
export function confirmEstimates(preview) {
  const e = preview.estimate || {};
  const rows = [
    ["duration", durationText(e)],
    ["length", withUnit(e.length_m, "m", 1)],
    ["depth range", e.depth_min_m == null ? "unknown" : `${num(e.depth_min_m, 2)} to ${num(e.depth_max_m, 2)} m`],
    ["battery use", withUnit(e.battery_pct, "%", 2)],
  ];
  // the copies and p(delivered): the line below (copies.js copiesLine), once
  return el("dl", { class: "kv estimates confirm-estimates", testid: "confirm-estimates" },
    ...estimateRows(e, rows));
}
