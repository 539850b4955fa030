// The training panel (simulated vehicle only): channel, current, time scale, reset, scenarios.

import { api } from "./api.js";
import { $, el, notify, notifyError, applyAuth } from "./ui.js";

// [key, label, unit, attributes]; an empty range_m means no range limit (sent as null).
const CHANNEL = [
  ["ber", "bit error rate", "", { min: 0, max: 0.5, step: "any" }],
  ["burst_rate", "burst probability per frame", "", { min: 0, max: 1, step: "any" }],
  ["burst_length_bits", "burst length", "bits", { min: 1, max: 100, step: 1 }],
  ["loss", "frame loss probability", "", { min: 0, max: 1, step: "any" }],
  ["range_m", "link range (empty: unlimited)", "m", { min: 0, step: "any" }],
  ["delay_s", "extra delay", "s", { min: 0, step: "any" }],
  ["bitrate_bps", "bitrate", "b/s", { min: 1, step: "any" }],
];
const CURRENT = [
  ["north_mps", "current north", "m/s", { step: "any" }],
  ["east_mps", "current east", "m/s", { step: "any" }],
  ["speed_sigma_mps", "speed drift sigma", "m/s", { min: 0, step: "any" }],
  ["direction_sigma_deg", "direction drift sigma", "deg", { min: 0, step: "any" }],
];
const TIME = [["time_scale", "time scale (0 pauses)", "x", { min: 0, max: 50, step: "any" }]];

function numberField([key, label, unit, attrs]) {
  const id = `training-${key}`;
  return el("div", { class: "field" },
    el("label", { for: id }, label, unit ? el("span", { class: "muted" }, ` (${unit})`) : null),
    el("div", { class: "input-unit" },
      el("input", { id, testid: id, name: key, type: "number", inputmode: "decimal", ...attrs }),
      unit ? el("span", { class: "unit", "aria-hidden": "true" }, unit) : null));
}

function read(spec) {
  const out = {};
  for (const [key] of spec) {
    const text = $(`training-${key}`).value.trim();
    out[key] = text === "" ? null : Number(text);
  }
  return out;
}

function fill(spec, values) {
  if (!values) return;
  for (const [key] of spec) {
    if (key in values) $(`training-${key}`).value = values[key] ?? "";
  }
}

async function put(path, body, what) {
  try {
    await api(path, { method: "PUT", body });
    notify(`${what} applied`);
  } catch (err) {
    notifyError(what, err);
  }
}

export function initTraining() {
  $("channel-fields").replaceChildren(...CHANNEL.map(numberField));
  $("current-fields").replaceChildren(...CURRENT.map(numberField));
  $("time-fields").replaceChildren(...TIME.map(numberField));
  $("training-channel").addEventListener("submit", (e) => {
    e.preventDefault();
    put("/api/training/channel", read(CHANNEL), "channel");
  });
  $("training-current").addEventListener("submit", (e) => {
    e.preventDefault();
    put("/api/training/current", read(CURRENT), "current");
  });
  $("training-time").addEventListener("submit", (e) => {
    e.preventDefault();
    put("/api/training/time_scale", read(TIME), "time scale");
  });
  $("training-reset").addEventListener("click", async () => {
    try {
      await api("/api/training/reset", { method: "POST" });
      notify("vehicle reset to its start (a new dive)");
    } catch (err) {
      notifyError("reset", err);
    }
  });
}

/** Show the panel in training mode and fill it from GET /api/training. */
export async function loadTraining(mode) {
  const panel = $("training-panel");
  panel.hidden = mode !== "training";
  if (panel.hidden) return;
  let t;
  try {
    t = await api("/api/training");
  } catch (err) {
    notifyError("training settings", err);
    return;
  }
  if (t && t.enabled === false) {
    panel.hidden = true;
    return;
  }
  fill(CHANNEL, t.channel);
  fill(CURRENT, t.current);
  fill(TIME, { time_scale: t.time_scale });
  const names = Array.isArray(t.scenarios) ? t.scenarios : [];
  $("scenarios").replaceChildren(...names.map((item) => {
    const name = typeof item === "string" ? item : item.name;
    const doc = typeof item === "string" ? "" : item.doc || item.description || "";
    return el("button", {
      type: "button", testid: `scenario-${name}`, dataset: { auth: "" }, title: doc || `reset, then run the ${name} scenario`,
      onclick: () => runScenario(name),
    }, name);
  }));
  if (!names.length) $("scenarios").append(el("span", { class: "hint" }, "no scenarios"));
  applyAuth(undefined, panel);
}

async function runScenario(name) {
  try {
    await api(`/api/training/scenario/${encodeURIComponent(name)}`, { method: "POST" });
    notify(`scenario ${name} started: watch the command list`);
  } catch (err) {
    notifyError(`scenario ${name}`, err);
  }
}
