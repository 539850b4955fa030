// The predicted track: after each successful preview, POST /api/predict (the same body) runs
// the twin from the vehicle's current state, faster than real time. It takes hundreds of ms,
// so it is debounced, the previous request is aborted, and a busy console (503) is asked once
// more. The chart draws the track; #prediction shows planned against predicted duration and
// the largest deviation from the planned path, or why there is no prediction.

import { api } from "./api.js";
import { showPredicted, latLngs } from "./chart.js";
import { $, el, on, num } from "./ui.js";

const DEBOUNCE_MS = 400;
const BUSY_RETRY_MS = 1500;

const state = { timer: null, controller: null, seq: 0 };

/** "138 s" below ten minutes, "12 min 5 s" above. */
export function duration(s) {
  if (s === null || s === undefined || !Number.isFinite(Number(s))) return "–";
  const v = Number(s);
  if (v < 600) return `${num(v, v < 10 ? 1 : 0)} s`;
  const m = Math.floor(v / 60);
  return `${m} min ${Math.round(v - m * 60)} s`;
}

function row(label, value, testid, title) {
  return el("div", { title }, el("dt", {}, label), el("dd", { testid }, value));
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
  const planned = p.planned_duration_s;
  const predicted = p.duration_s;
  const repeats = planned === null || planned === undefined;
  const rows = [
    row("planned", repeats ? "repeats (no end)" : duration(planned), "prediction-planned", "the path's own duration, at the commanded speed"),
  ];
  if (predicted === null || predicted === undefined || p.completes === false) {
    const text = repeats ? `repeats: ${duration(p.horizon_s)} predicted` : `not done within ${duration(p.horizon_s)}`;
    rows.push(row("predicted", text, "prediction-predicted", "the twin's run of the command from the vehicle's state now, over a bounded horizon"));
  } else {
    const ratio = planned > 0 ? ` (${num(predicted / planned, 2)}x)` : "";
    rows.push(row("predicted", `${duration(predicted)}${ratio}`, "prediction-predicted", "the twin's run of the command from the vehicle's state now"));
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
