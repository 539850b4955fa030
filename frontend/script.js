// Mission scripts: ordered steps (pattern, parameters, trigger), preview, save/load, onboard
// export, and running them in auto or step mode. The script (name + steps) is kept in
// localStorage on every change and restored when the page loads.

import { api } from "./api.js";
import { paramForm, fillPatternSelect, defaultParams, commandText } from "./form.js";
import { $, el, download, notify, notifyError, applyAuth, setOff, on } from "./ui.js";
import { REPEATING, SCRIPT_FORMAT, SCRIPT_VERSION, TRIGGERS, completionRefusal, parseScript, triggerText } from "./script_format.js";
import { drawScriptPlan } from "./script_plan.js";
import { runStepText, timelineText } from "./script_text.js";

/** localStorage key of the script being authored. */
export const STORE_KEY = "nemesys.script";

let steps = []; // [{pattern, params, trigger: {kind, t_s}, vehicle?}] (vehicle: a fleet's, named by every step)
let pollTimer = null;

/** Keep the script in localStorage (best effort: a full or disabled storage only warns once). */
let storeWarned = false;
function persist() {
  try {
    localStorage.setItem(STORE_KEY, JSON.stringify(scriptDocument()));
  } catch (err) {
    if (!storeWarned) notify(`the script cannot be kept across reloads: ${err.message}`, "warn");
    storeWarned = true;
  }
}

/** Restore the stored script; corrupt or old data is dropped with a notice, never a crash. */
function restore() {
  let text = null;
  try {
    text = localStorage.getItem(STORE_KEY);
  } catch {
    return;
  }
  if (!text) return;
  try {
    const parsed = parseScript(text);
    $("script-name").value = parsed.name;
    steps = parsed.steps;
    if (steps.length) notify(`restored the script ${parsed.name}: ${steps.length} step${steps.length === 1 ? "" : "s"}`);
  } catch (err) {
    steps = [];
    try { localStorage.removeItem(STORE_KEY); } catch { /* nothing more to do */ }
    notify(`the stored script could not be restored (${err.message}): starting with an empty script`, "warn");
  }
}

function clearScript() {
  if (!steps.length) return;
  const n = steps.length;
  steps = [];
  renderSteps();
  $("script-timeline").replaceChildren();
  $("script-plan").hidden = true;
  notify(`script cleared (${n} step${n === 1 ? "" : "s"})`);
}

export function scriptDocument() {
  return {
    format: SCRIPT_FORMAT,
    version: SCRIPT_VERSION,
    name: $("script-name").value.trim() || "mission",
    steps: steps.map((s) => ({
      pattern: s.pattern,
      params: { ...s.params },
      trigger: { kind: s.trigger.kind, t_s: s.trigger.kind === "at" ? s.trigger.t_s : null },
      ...(s.vehicle ? { vehicle: s.vehicle } : {}),
    })),
  };
}

/** Add a step from the authoring form ({pattern, params, vehicle?}: with a fleet, the
 *  selected vehicle, which the step names; a run drives one vehicle, as the console checks). */
export function addStep(command) {
  if (!command || !command.pattern) return;
  const prev = steps[steps.length - 1];
  // on completion of the previous step, unless it repeats (it never completes): then on go
  const afterRepeating = Boolean(prev && REPEATING.has(prev.pattern));
  steps.push({
    pattern: command.pattern,
    params: { ...command.params },
    trigger: !prev ? { kind: "at", t_s: 0 } : afterRepeating ? { kind: "operator", t_s: null } : { kind: "after_previous", t_s: null },
    ...(command.vehicle ? { vehicle: command.vehicle } : {}),
  });
  renderSteps();
  notify(afterRepeating
    ? `step ${steps.length} added: ${command.pattern}, on the operator's go (step ${steps.length - 1}, a ${prev.pattern}, repeats until retasked: it never completes)`
    : `step ${steps.length} added: ${command.pattern}${command.vehicle ? ` to ${command.vehicle}` : ""}`);
}

function move(i, by) {
  const j = i + by;
  if (j < 0 || j >= steps.length) return;
  [steps[i], steps[j]] = [steps[j], steps[i]];
  renderSteps();
  $(`script-step-${j}`).querySelector(by < 0 ? ".up" : ".down")?.focus();
}

function remove(i) {
  steps.splice(i, 1);
  renderSteps();
}

function stepRow(step, i) {
  const prefix = `script-step-${i}-`;
  const patternSelect = el("select", { id: `${prefix}pattern`, testid: `${prefix}pattern`, "aria-label": `step ${i + 1} pattern` });
  fillPatternSelect(patternSelect, step.pattern);
  const summary = el("summary", {}, commandText(step));
  const formBox = el("div", { class: "param-form" });
  let form;
  const build = () => {
    form = paramForm(formBox, step.pattern, step.params, {
      prefix,
      onChange: () => {
        step.params = form.read();
        summary.textContent = commandText(step);
        persist();
      },
    });
  };
  build();
  patternSelect.addEventListener("change", () => {
    step.pattern = patternSelect.value;
    step.params = defaultParams(step.pattern);
    renderSteps(); // the next step's "on completion" may now be refused
  });

  const trigger = el("select", { id: `${prefix}trigger`, testid: `${prefix}trigger`, "aria-label": `step ${i + 1} trigger` },
    ...TRIGGERS.map(([k, label]) => el("option", { value: k }, label)));
  trigger.value = step.trigger.kind;
  const time = el("input", {
    id: `${prefix}t`, testid: `${prefix}t`, type: "number", min: 0, step: "any", inputmode: "decimal",
    "aria-label": `step ${i + 1} time from the run's start (s)`, hidden: step.trigger.kind !== "at",
  });
  time.value = step.trigger.t_s ?? 0;
  const unit = el("span", { class: "unit", hidden: step.trigger.kind !== "at" }, "s from the run's start");
  const check = el("p", { class: "step-check", testid: `${prefix}check`, hidden: true });
  const timing = el("p", { class: "step-timing hint", testid: `${prefix}timing`, hidden: true });
  const refusal = completionRefusal(steps, i);
  if (refusal) showCheck(check, "error", refusal);
  trigger.addEventListener("change", () => {
    const was = step.trigger.kind;
    const why = completionRefusal(steps.map((s, k) => (k === i ? { ...s, trigger: { kind: trigger.value } } : s)), i);
    if (why) { // refused: the step keeps its trigger
      trigger.value = was;
      showCheck(check, "error", why);
      notify(why, "warn");
      return;
    }
    check.hidden = true; // accepted: a refusal or an earlier check no longer applies
    step.trigger.kind = trigger.value;
    time.hidden = unit.hidden = trigger.value !== "at";
    step.trigger.t_s = trigger.value === "at" ? Number(time.value) || 0 : null;
    persist();
  });
  time.addEventListener("input", () => {
    step.trigger.t_s = time.value === "" ? 0 : Number(time.value);
    persist();
  });

  return el("li", { class: "script-step", id: `script-step-${i}`, testid: `script-step-${i}` },
    el("div", { class: "step-head" },
      el("strong", {}, `${i + 1}.`), patternSelect, trigger, time, unit,
      step.vehicle ? el("span", { class: "cmd-vehicle", testid: `${prefix}vehicle`, title: "the vehicle this step is sent to" }, `to ${step.vehicle}`) : null,
      el("span", { class: "step-buttons" },
        el("button", { type: "button", class: "small up", testid: `${prefix}up`, disabled: i === 0, "aria-label": `move step ${i + 1} up`, onclick: () => move(i, -1) }, "↑"),
        el("button", { type: "button", class: "small down", testid: `${prefix}down`, disabled: i === steps.length - 1, "aria-label": `move step ${i + 1} down`, onclick: () => move(i, 1) }, "↓"),
        el("button", { type: "button", class: "small", testid: `${prefix}remove`, "aria-label": `remove step ${i + 1}`, onclick: () => remove(i) }, "Remove"))),
    el("details", {}, summary, formBox),
    timing,
    check);
}

function showCheck(box, kind, text) {
  box.hidden = false;
  box.className = `step-check ${kind}`;
  box.textContent = text;
}

function renderSteps() {
  const list = $("script-steps");
  list.replaceChildren(...steps.map(stepRow)); // empty: CSS shows "no steps yet"
  persist();
}

// ---- preview, files, export ----

/** Put 422 errors (loc [..., "steps", i, ..., name]) next to the step they name. */
function showStepErrors(err) {
  for (const d of Array.isArray(err.detail) ? err.detail : []) {
    const loc = Array.isArray(d.loc) ? d.loc : [];
    const at = loc.indexOf("steps");
    const i = at >= 0 ? Number(loc[at + 1]) : NaN;
    const box = Number.isInteger(i) ? $("script-step-" + i)?.querySelector(".step-check") : null;
    if (box) showCheck(box, "error", `${loc.slice(at + 2).join(".") || "step"}: ${d.msg}`);
  }
}

function clearStepChecks() {
  document.querySelectorAll("#script-steps .step-check").forEach((box, i) => {
    const why = completionRefusal(steps, i);
    if (why) showCheck(box, "error", why);
    else box.hidden = true;
  });
}

function show3dView() {
  $("viewer-box")?.scrollIntoView({ block: "nearest" });
}

async function previewScript() {
  clearStepChecks();
  try {
    const r = await api("/api/scripts/preview", { method: "POST", body: scriptDocument() });
    const timeline = Array.isArray(r && r.timeline) ? r.timeline : [];
    $("script-timeline").replaceChildren(...(timeline.length
      ? timeline.map((e, i) => el("li", {
        testid: `script-timeline-${i}`,
        dataset: e && e.step != null ? { step: String(e.step) } : {},
      }, timelineText(e)))
      : [el("li", { class: "hint" }, "empty timeline")]));
    const previewed = Array.isArray(r && r.steps) ? r.steps : [];
    drawScriptPlan($("script-plan"), r && r.path, previewed, show3dView);
    previewed.forEach((s, i) => {
      const row = $("script-step-" + i);
      const timing = row?.querySelector(".step-timing");
      if (timing && s && s.timing_text) {
        timing.hidden = false;
        timing.textContent = s.timing_text;
      }
      const box = row?.querySelector(".step-check");
      const v = s && Array.isArray(s.violations) ? s.violations : [];
      if (box && v.length) {
        box.hidden = false;
        box.className = "step-check warn";
        box.textContent = v.map((x) => `${x.param}: ${x.message}`).join("; ");
      }
    });
    notify("script preview drawn above the steps and in the 3D view");
  } catch (err) {
    if (err.status === 422) showStepErrors(err);
    notifyError("script preview", err);
  }
}

function fileName(ext) {
  return `${(scriptDocument().name || "mission").replace(/[^A-Za-z0-9_.-]+/g, "_")}${ext}`;
}

function saveScript() {
  download(fileName(".nemesys-script.json"), JSON.stringify(scriptDocument(), null, 2) + "\n");
}

async function loadScript(event) {
  const file = event.target.files && event.target.files[0];
  event.target.value = "";
  if (!file) return;
  try {
    const parsed = parseScript(await file.text());
    $("script-name").value = parsed.name;
    steps = parsed.steps;
    renderSteps();
    notify(`loaded ${parsed.name}: ${steps.length} steps`);
  } catch (err) {
    notify(`could not load ${file.name}: ${err.message}`, "error");
  }
}

async function exportOnboard() {
  try {
    const r = await api("/api/scripts/export", { method: "POST", body: scriptDocument() });
    if (typeof r === "string") download(fileName(".onboard.txt"), r, "text/plain");
    else download(fileName(".onboard.json"), JSON.stringify(r, null, 2) + "\n");
  } catch (err) {
    if (err.status === 422) showStepErrors(err);
    notifyError("onboard export", err);
  }
}

// ---- running ----

async function runScript() {
  if (!steps.length) {
    notify("the script has no steps", "warn");
    return;
  }
  const mode = $("script-step-mode").checked ? "step" : "auto";
  try {
    renderRun(await api("/api/scripts/run", { method: "POST", body: { script: scriptDocument(), mode } }));
  } catch (err) {
    if (err.status === 422) showStepErrors(err);
    notifyError("run script", err);
  }
}

async function control(path, what) {
  try {
    renderRun(await api(path, { method: "POST" }));
  } catch (err) {
    notifyError(what, err);
  }
  pollRun();
}

export async function pollRun() {
  try {
    renderRun(await api("/api/scripts/run"));
  } catch (err) {
    if (err.status !== 404) notifyError("script run state", err);
    renderRun(null);
  }
}

function renderRun(run) {
  const running = Boolean(run && run.running);
  const total = run && Array.isArray(run.steps) ? run.steps.length : 0;
  const state = $("script-run-state");
  state.textContent = run && typeof run.summary === "string" && (running || total) ? run.summary : "not running";
  state.dataset.outcome = (run && run.outcome) || "";
  const next = running && run.next ? run.next : null;
  const proposal = $("script-next-proposal");
  proposal.hidden = !next;
  proposal.textContent = next ? `Proposed next: ${commandText(next)}${next.vehicle ? ` to ${next.vehicle}` : ""}${next.trigger ? ` (${triggerText(next.trigger)})` : ""}` : "";
  setOff($("script-next"), !(running && run.mode === "step" && next));
  setOff($("script-stop"), !running);
  setOff($("script-run"), running);
  $("script-run-steps").replaceChildren(...(running || total ? (run.steps || []).map((s, i) =>
    el("li", { testid: `script-run-step-${i}`, class: s && s.state ? `st-${s.state}` : "" },
      runStepText(s, i))) : []));
  clearTimeout(pollTimer);
  pollTimer = running ? setTimeout(pollRun, 1000) : null;
}

export function initScript() {
  restore();
  renderSteps();
  $("script-name").addEventListener("input", persist);
  if (!$("script-clear")) { // a Clear button beside the export (kept out of index.html's layout)
    $("script-export").after(el("button", { type: "button", id: "script-clear", testid: "script-clear" }, "Clear script"));
  }
  $("script-clear").addEventListener("click", clearScript);
  $("script-preview").addEventListener("click", previewScript);
  $("script-save").addEventListener("click", saveScript);
  $("script-load").addEventListener("change", loadScript);
  $("script-export").addEventListener("click", exportOnboard);
  $("script-run").addEventListener("click", runScript);
  $("script-next").addEventListener("click", () => control("/api/scripts/run/next", "send next"));
  $("script-stop").addEventListener("click", () => control("/api/scripts/run/stop", "stop"));
  applyAuth(undefined, $("script-panel"));
  // the operator's command ended the run (backend/scripts/guard.py): its state, at once
  on("log_event", (e) => e && e.kind === "script_stopped" && pollRun());
  pollRun();
}
