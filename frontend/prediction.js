// The predicted track: after each successful preview, POST /api/predict (the same body) runs
// the twin from the vehicle's current state, faster than real time. It takes hundreds of ms,
// so it is debounced, the previous request is aborted, and a busy console (503) is asked once
// more. The chart draws the track; #prediction shows the command's three durations side by
// side (planned: the plan's clock; estimated: as the vehicle's profile flies it; predicted:
// the twin's run), why they differ where they differ by more than 20 %, and the largest
// deviation from the planned path, or why there is no prediction.

import { api } from "./api.js";
import { showPredicted, latLngs } from "./chart.js";
import { $, el, on, num } from "./ui.js";

const DEBOUNCE_MS = 400;
const BUSY_RETRY_MS = 1500;

const state = { timer: null, controller: null, seq: 0 };

/** A duration, always in seconds ("138 s", "2431 s"; "7.5 s" below ten): every duration on
 *  the page (estimates, join, prediction) reads the same way. */
export function duration(s) {
  if (s === null || s === undefined || !Number.isFinite(Number(s))) return "–";
  const v = Number(s);
  return `${num(v, v < 10 ? 1 : 0)} s`;
}

function row(label, value, testid, title, wide = false) {
  return el("div", { title, class: wide ? "wide" : null }, el("dt", {}, label), el("dd", { testid }, value));
}

function show(rows, status = "") {
  const box = $("prediction");
  box.replaceChildren(...rows);
  box.dataset.state = status;
}

function reason(text, status) {
  show([row("prediction", text, "prediction-reason", text)], status);
}

// [short text for the one-line row, the whole story on hover]
const OUTCOMES = {
  lost: ["not reached", "the frame would not reach the vehicle (out of the link's range): it keeps what it runs"],
  rejected: ["rejected", "the vehicle would reject it"],
  duplicate: ["already running", "the vehicle already runs it (a duplicate)"],
};

function render(p) {
  const estimate = p.estimate_duration_s;
  const predicted = p.duration_s;
  // a repeating pattern never ends: its durations are the join and one lap, all three alike
  const span = p.repeats ? " (join + 1 lap)" : "";
  const rows = [
    row(`planned duration${span}`, duration(p.planned_duration_s), "prediction-planned",
      "by the plan's own clock: the path's times, at the commanded speed"),
    row(`estimated duration${span}`, duration(estimate), "prediction-estimate",
      "as the vehicle's profile flies the plan (the preview's estimate)"),
  ];
  if (predicted === null || predicted === undefined || p.completes === false) {
    rows.push(row(`predicted duration${span}`, `not done within ${duration(p.horizon_s)}`, "prediction-predicted",
      "the twin's run of the command from the vehicle's state now, over a bounded horizon"));
  } else {
    const ratio = estimate > 0 ? ` (${num(predicted / estimate, 2)}x the estimate)` : "";
    rows.push(row(`predicted duration${span}`, `${duration(predicted)}${ratio}`, "prediction-predicted",
      "the twin's run of the command from the vehicle's state now"));
  }
  const notes = Array.isArray(p.duration_notes) ? p.duration_notes : [];
  if (notes.length) {
    rows.push(row("why", notes.join("; "), "prediction-notes", "why the prediction and the estimate differ by more than 20 %", true));
  }
  rows.push(
    row(
      "max deviation",
      Number.isFinite(p.max_deviation_m) ? `${num(p.max_deviation_m, 1)} m` : "–",
      "prediction-deviation",
      "the predicted track's largest distance from the planned path",
    ),
  );
  if (p.outcome && p.outcome !== "accepted") {
    const [short, why] = OUTCOMES[p.outcome] || [p.outcome, p.outcome];
    rows.push(row("outcome", short, "prediction-outcome", p.reason ? `${why}: ${p.reason}` : why));
  }
  show(rows, p.outcome && p.outcome !== "accepted" ? "error" : "done");
  const box = $("prediction");
  box.title = Array.isArray(p.assumptions) && p.assumptions.length ? `assumes: ${p.assumptions.join("; ")}` : "";
  showPredicted(latLngs(p));
}

async function predict(body, seq, retried = false) {
  if (state.controller) state.controller.abort();
  const controller = new AbortController();
  state.controller = controller;
  reason("predicting…", "pending");
  try {
    const p = await api("/api/predict", { method: "POST", body, signal: controller.signal });
    if (seq !== state.seq) return;
    render(p);
  } catch (err) {
    if ((err && err.name === "AbortError") || seq !== state.seq) return;
    if (err.status === 503 && !retried) {
      const wait = Number(err.retryAfter) > 0 ? Number(err.retryAfter) * 1000 : BUSY_RETRY_MS;
      reason("predicting… (the console is busy: trying again)", "pending");
      state.timer = setTimeout(() => seq === state.seq && predict(body, seq, true), wait);
      return;
    }
    showPredicted(null);
    const why = err.status === 404 ? "this console does not offer predictions (/api/predict)" : err.message;
    reason(`no prediction: ${why}`, "error");
  }
}

/** Listen to the page's previews; predict after each successful one. */
export function initPrediction() {
  reason("no prediction yet: author a command", "idle");
  on("preview", ({ preview, command }) => {
    const seq = ++state.seq;
    clearTimeout(state.timer);
    if (state.controller) state.controller.abort();
    state.controller = null;
    if (!preview) {
      showPredicted(null);
      reason("no prediction: the preview failed", "idle");
      return;
    }
    showPredicted(null); // the previous command's track is not this one's
    reason("predicting…", "pending");
    state.timer = setTimeout(() => predict(command, seq), DEBOUNCE_MS);
  });
}
