// Authoring: pattern picker, parameter form, live preview (bits, hex, airtime, estimates,
// checks; the backend draws the 3D preview in the viewer) and the confirmed send: of the form's
// command, or a retry of a logged one (the same dialog, checked from where the vehicle is now).
// With a fleet every preview, prediction, send and retry names its vehicle (fleet.js): the
// selected one, or the retried record's; switching vehicles previews again from the new one.

import { api, ApiError } from "./api.js";
import { initCopies, readCopies, copiesLine } from "./copies.js";
import { withVehicle } from "./fleet.js";
import { dictionary, fillPatternSelect, paramForm, defaultParams, unitOf } from "./form.js";
import { $, el, num, withUnit, delta, notify, notifyError, resolved, slug, canWrite, emit, latLon, on } from "./ui.js";
import { confirmChecks, isHard, kindText, skippedTitle, withinLimits } from "./checks.js";
import { confirmEstimates, renderEstimates } from "./estimates.js";

const state = {
  form: null,
  pattern: "",
  remembered: new Map(), // pattern -> last values typed for it
  preview: null, // the last successful preview response
  previewError: null, // the last ApiError of the preview
  seq: 0,
  controller: null,
  lastKey: "", // the command last previewed (JSON), to skip an edit's change event
  errorTimer: null,
  onSent: () => {},
  // what the open confirm dialog sends: {pattern, params, retryOf, vehicle?} (retryOf: null,
  // or the id of the logged command a retry repeats as a new command; vehicle: a fleet's)
  pending: null,
};

/** The form's command, naming the selected vehicle with a fleet. */
export function current() {
  return withVehicle({ pattern: state.pattern, params: state.form ? state.form.read() : {} });
}

// An edit previews at once: the preview is a millisecond's work on the console, and the 150 ms
// debounce the page had was most of the edit-to-bits time (bench/edit_latency.py). A newer edit
// aborts the older request. What a half-typed value gets (a 422: "0." on the way to "0.5") is
// shown only if no edit follows within ERROR_SHOW_MS; meanwhile the last frame is dimmed.
const ERROR_SHOW_MS = 300;

/** A form edit: preview, unless it is the change event of values already previewed. */
function onEdit() {
  if (state.form && JSON.stringify(current()) === state.lastKey) return;
  runPreview({ errorDelayMs: ERROR_SHOW_MS });
}

/** Build the picker from the dictionary. onSent(record) is told about every queued command. */
export function initAuthoring({ onSent }) {
  state.onSent = onSent;
  const select = $("pattern-select");
  const first = dictionary.list.find((p) => (p.fields || []).length) || dictionary.list[0];
  fillPatternSelect(select, first && first.name);
  select.addEventListener("change", () => choosePattern(select.value));
  $("param-form").addEventListener("submit", (e) => {
    e.preventDefault();
    runPreview();
  });
  $("send-button").addEventListener("click", openConfirm);
  $("confirm-cancel").addEventListener("click", () => $("confirm-dialog").close());
  $("confirm-send").addEventListener("click", confirmSend);
  $("confirm-override").addEventListener("change", updateConfirmButton);
  initCopies();
  on("vehicle_selected", () => state.pattern && runPreview()); // from that vehicle's believed position
  if (select.value) choosePattern(select.value);
}

/** Switch pattern, keeping values typed for it before and same-named fields (speed, depth). */
export function choosePattern(name, values) {
  if (state.form) state.remembered.set(state.pattern, state.form.read());
  const carried = state.form ? state.form.read() : {};
  const start = { ...defaultParams(name), ...pick(carried, name), ...(state.remembered.get(name) || {}), ...(values || {}) };
  state.pattern = name;
  $("pattern-select").value = name;
  const p = dictionary.byName.get(name);
  $("pattern-doc").textContent = p ? p.doc || "" : "";
  state.form = paramForm($("param-form"), name, start, { onChange: onEdit });
  runPreview();
}

function pick(values, pattern) {
  const p = dictionary.byName.get(pattern);
  const names = new Set(((p && p.fields) || []).filter((f) => f.kind !== "choice").map((f) => f.name));
  return Object.fromEntries(Object.entries(values).filter(([k]) => names.has(k)));
}

/** Preview the form's command; a failure is drawn after `errorDelayMs` if no newer preview
 *  started meanwhile (0: at once, as the Send button needs it). */
export async function runPreview({ errorDelayMs = 0 } = {}) {
  if (!state.pattern) return;
  if (state.controller) state.controller.abort();
  clearTimeout(state.errorTimer);
  const controller = new AbortController();
  state.controller = controller;
  const seq = ++state.seq;
  const body = current();
  state.lastKey = JSON.stringify(body);
  try {
    const preview = await api("/api/preview", { method: "POST", body, signal: controller.signal });
    if (seq !== state.seq) return;
    state.preview = preview;
    state.previewError = null;
    renderPreview(preview);
    resolved("parameters"); // the values a Send was refused for are fixed: its message goes
    $("estimates").dataset.command = state.lastKey; // whose estimates these are (tests, bench)
    emit("preview", { preview, command: body });
  } catch (err) {
    if (err.name === "AbortError" || seq !== state.seq) return;
    state.preview = null;
    state.previewError = err;
    emit("preview", { preview: null, command: body });
    if (errorDelayMs <= 0) {
      renderPreviewError(err);
      return;
    }
    setStale(true); // the frame shown is not this value's
    state.errorTimer = setTimeout(() => seq === state.seq && renderPreviewError(err), errorDelayMs);
  }
}

/** Dim the frame and estimates while they are not the form's values (a failure not shown yet). */
function setStale(stale) {
  for (const id of ["bits-strip", "frame-hex", "estimates"]) $(id).classList.toggle("stale", stale);
}

// ---- rendering the preview ----

function sectionKind(section, fieldNames) {
  if (["preamble", "delimiter", "pattern", "crc", "parity", "guard"].includes(section.name)) return section.name;
  if (fieldNames.includes(section.name)) return "field";
  return "unused";
}

export function renderBits(container, response) {
  const bits = response.bits || "";
  const sections = Array.isArray(response.sections) ? response.sections : [];
  const p = dictionary.byName.get(response.pattern);
  const fieldNames = ((p && p.fields) || []).map((f) => f.name);
  const spans = sections.map((s, i) => {
    const kind = sectionKind(s, fieldNames);
    const length = s.length ?? (s.bits || "").length;
    const last = s.start + length - 1;
    const label = kind === "field" ? s.name : s.name.replace(" (unused)", "");
    return el("span", {
      class: `sec sec-${kind}${kind === "field" ? ` field-${fieldNames.indexOf(s.name) % 6}` : ""}`,
      testid: `bits-${slug(s.name)}`,
      title: `${s.name}: bits ${s.start}-${last} (${length} bits)`,
      dataset: { label, index: String(i) },
    }, s.bits || bits.slice(s.start, s.start + length));
  });
  container.replaceChildren(...(spans.length ? spans : [el("span", { class: "sec" }, bits)]));
}

/** "(100 bits)", or a fleet's addressed frame: "(108 bits, to address 2)" (0: all vehicles). */
function frameSize(r) {
  const size = r.frame_bits ?? (r.bits || "").length;
  const section = (Array.isArray(r.sections) ? r.sections : []).find((s) => s.name === "address");
  if (!section || !/^[01]+$/.test(section.bits || "")) return `(${size} bits)`;
  const address = parseInt(section.bits, 2);
  return `(${size} bits, to ${address === 0 ? "all vehicles, address 0" : `address ${address}`})`;
}

function renderPreview(r) {
  setStale(false);
  renderBits($("bits-strip"), r);
  $("frame-hex").textContent = r.hex || "–";
  $("frame-size").textContent = frameSize(r);
  $("airtime").textContent = r.airtime_ms == null ? "–" : `${num(r.airtime_ms, 3)} ms at ${num(r.bitrate_bps, 0)} b/s`;
  renderEstimates(r.estimate);
  renderStart(r.start);
  $("estimates").dataset.pattern = r.pattern || ""; // whose preview is shown (tests wait on it)
  const violations = Array.isArray(r.violations) ? r.violations : [];
  state.form.setSnaps(r.snaps);
  state.form.setErrors(new Map());
  state.form.setWarnings(new Set(violations.map((v) => v.param)));
  renderChecks(violations.map(violationItem), violations.length ? "" : withinLimits(r), skippedTitle(r));
}

/** Where the preview starts, said when it is not the last fix: the console's belief (its
 *  "start": dead-reckoned, or assumed), in its words. */
export function startText(start) {
  if (!start || start.source === "telemetry") return "";
  if (start.source === "assumed") return `starts from an assumed position: ${start.basis}`;
  const sigma = Number.isFinite(start.sigma_m) ? ` ± ${num(start.sigma_m, 1)} m` : "";
  return `starts from the dead-reckoned position${sigma} (${num(start.age_s, 0)} s since the last fix)`;
}

function renderStart(start) {
  const node = $("preview-start");
  node.textContent = startText(start);
  node.hidden = !node.textContent;
  node.dataset.source = start ? start.source : "";
}

function renderPreviewError(err) {
  renderStart(null);
  setStale(false);
  $("estimates").dataset.command = "";
  for (const id of ["bits-strip", "estimates"]) $(id).replaceChildren();
  $("frame-hex").textContent = "–";
  $("airtime").textContent = "–";
  const items = err instanceof ApiError && err.status === 422 ? err.items : [{ param: "", msg: err.message }];
  if (state.form) {
    state.form.setSnaps([]);
    state.form.setWarnings(new Set());
    state.form.setErrors(new Map(items.filter((i) => i.param).map((i) => [i.param, i.msg])));
  }
  renderChecks(items.map((i) => ({ text: i.param ? `${i.param}: ${i.msg}` : i.msg, kind: "error", param: i.param })), "");
}

function violationItem(v) {
  const unit = v.unit || unitOf(state.pattern, v.param);
  const facts = v.allowed ? ` (allowed: ${v.allowed})`
    : v.limit !== undefined ? ` (${withUnit(v.value, unit)}, limit ${withUnit(v.limit, unit)})` : "";
  const hard = isHard(v);
  return {
    param: v.param,
    kind: hard ? "error" : "warn",
    // the planner's message usually names the parameter itself ("depth = 150 m ..."): once
    text: `${v.message && v.message.startsWith(v.param) ? "" : `${v.param}: `}${v.message || "outside the limits"}${facts} [${kindText(hard)}]`,
  };
}

function renderChecks(items, okText, okTitle) {
  const list = $("violations");
  if (!items.length) {
    list.replaceChildren(el("li", { class: "ok", title: okTitle || null }, okText || "–"));
    return;
  }
  list.replaceChildren(...items.map((i) => el("li", { class: i.kind, dataset: { param: i.param || "" } }, i.text)));
}

// ---- the confirm step ----

async function openConfirm() {
  if (!canWrite()) return;
  await runPreview();
  const err = state.previewError;
  if (err && err.status === 422) {
    notify("Fix the parameters first: " + err.items.map((i) => `${i.param} ${i.msg}`).join("; "), "error", "parameters");
    const bad = err.items.find((i) => i.param);
    if (bad && state.form) state.form.focus(bad.param);
    return;
  }
  showConfirm(state.preview, { ...current(), retryOf: null });
}

/** Retry: the confirm dialog for a new command with a logged one's pattern and values, from a
 *  fresh preview (the estimates and every check from where the vehicle is now). The form and
 *  its preview stay as the operator left them. */
export async function openRetry(record) {
  if (!canWrite()) return;
  // a fleet: to the record's own vehicle, named (none named: the console says which it needs)
  const command = withVehicle({ pattern: record.pattern, params: record.params || {}, retryOf: record.id }, record.vehicle ?? null);
  let preview = null;
  let error = null;
  try {
    preview = await api("/api/preview", { method: "POST", body: withVehicle({ pattern: command.pattern, params: command.params }, command.vehicle ?? null) });
  } catch (err) {
    error = err;
  }
  showConfirm(preview, command, error);
}

function showConfirm(preview, command, error = null) {
  state.pending = command;
  renderConfirm(preview, command, error);
  $("confirm-dialog").showModal();
}

function renderConfirm(preview, command, error) {
  const body = $("confirm-body");
  const overrideBox = $("confirm-override-box");
  $("confirm-override").checked = false;
  $("confirm-error").hidden = true;
  body.dataset.hard = "0";
  const parts = [];
  if (error instanceof ApiError && error.status !== 0) {
    // a retry's values the checks refuse outright (a 422): shown, and nothing can send them
    parts.push(el("ul", { class: "violations", testid: "confirm-preview-error" },
      ...error.items.map((i) => el("li", { class: "error" }, i.param ? `${i.param}: ${i.msg}` : i.msg))));
    overrideBox.hidden = true;
    body.dataset.hard = "1";
  } else if (!preview) {
    parts.push(el("p", { class: "warn" }, "No preview available (backend unreachable?): the command is checked when sent."));
    overrideBox.hidden = true;
  } else {
    const diff = preview.diff || {};
    parts.push(el("p", { testid: "confirm-summary" },
      "Active: ", el("strong", {}, diff.active || "none"), "  ->  new: ", el("strong", {}, preview.pattern)));
    const changes = Array.isArray(diff.changes) ? diff.changes : [];
    const active = Boolean(preview.diff);
    const changedPattern = active && diff.active !== preview.pattern;
    parts.push(changes.length
      ? el("ul", { class: "changes", testid: "confirm-changes" }, ...changes.map((c) =>
        el("li", { dataset: { param: c.param } }, changeText(c, preview.pattern))))
      : !active ? firstCommand(preview)
        : el("p", { class: "hint", testid: "confirm-changes" },
          changedPattern ? "New pattern, same parameter values." : "No parameter changes (a repeat)."));
    parts.push(confirmEstimates(preview));
    if (active) {
      parts.push(el("p", { testid: "confirm-deltas" },
        `against the running ${diff.active}: duration ${delta(diff.duration_delta_s, "s")}, length ${delta(diff.length_delta_m, "m")}`));
    }
    const from = preview.from;
    if (from && Number.isFinite(from.x_m) && Number.isFinite(from.y_m)) {
      const geo = latLon(from.lat_deg, from.lon_deg);
      parts.push(el("p", { class: "hint", testid: "confirm-from" },
        "starts from ", el("span", { class: "position" }, `x ${num(from.x_m, 1)} m north, y ${num(from.y_m, 1)} m east`),
        geo === "–" ? null : el("span", { class: "latlon" }, ` ${geo}`),
        startText(preview.start) ? el("span", { class: "warn-text", testid: "confirm-start" }, ` (${startText(preview.start)})`) : null));
    }
    parts.push(el("p", { class: "hint" }, `frame ${preview.hex || "–"}, ${num(preview.airtime_ms, 3)} ms on air`));
    const violations = Array.isArray(preview.violations) ? preview.violations : [];
    parts.push(...confirmChecks(preview, violations));
    overrideBox.hidden = !violations.some((v) => !isHard(v));
    body.dataset.hard = violations.some(isHard) ? "1" : "0";
  }
  parts.push(copiesLine(preview));
  const to = command.vehicle ? ` to ${command.vehicle}` : "";
  $("confirm-title").textContent = command.retryOf == null ? `Send ${command.pattern}${to}?`
    : `Retry command ${command.retryOf} (${command.pattern})${to} as a new command?`;
  $("confirm-send").textContent = `Confirm and send${to}`;
  body.replaceChildren(...parts);
  updateConfirmButton();
}

/** Nothing runs yet: every parameter is new; list them as they will be sent (snapped). */
function firstCommand(preview) {
  const params = Object.entries(preview.params || {});
  return el("div", { testid: "confirm-changes" },
    el("p", { class: "hint" }, "Nothing is running: every parameter is new."),
    params.length ? el("ul", { class: "changes" }, ...params.map(([k, v]) =>
      el("li", { dataset: { param: k } }, `${k}: ${withUnit(v, unitOf(preview.pattern, k))}`))) : null);
}

function changeText(c, pattern) {
  const unit = c.unit || unitOf(pattern, c.param) || unitOf(state.pattern, c.param);
  const old = c.old === null || c.old === undefined ? "(not set)" : withUnit(c.old, unit);
  return `${c.param}: ${old} -> ${withUnit(c.new, unit)}`;
}

function updateConfirmButton() {
  const hard = $("confirm-body").dataset.hard === "1";
  const needsOverride = !$("confirm-override-box").hidden && !$("confirm-override").checked;
  const button = $("confirm-send");
  button.disabled = hard || needsOverride;
  button.title = hard ? "a limit that cannot be overridden is violated" : needsOverride ? "tick “override limits” to send anyway" : "";
}

async function confirmSend() {
  const command = state.pending || { ...current(), retryOf: null };
  const retry = command.retryOf != null;
  const button = $("confirm-send");
  const { copies, error } = readCopies();
  if (error) {
    $("confirm-error").hidden = false;
    $("confirm-error").textContent = error;
    return;
  }
  button.disabled = true;
  const override = $("confirm-override").checked;
  const body = withVehicle(retry ? { override } : { pattern: command.pattern, params: command.params, override }, command.vehicle ?? null);
  if (copies !== null) body.copies = copies;
  const path = retry ? `/api/commands/${encodeURIComponent(command.retryOf)}/retry` : "/api/commands";
  try {
    const record = await api(path, { method: "POST", body });
    $("confirm-dialog").close();
    const id = record && record.id !== undefined ? ` (command ${record.id})` : "";
    resolved("send");
    const to = command.vehicle ? ` to ${command.vehicle}` : "";
    notify(retry ? `retry of command ${command.retryOf} (${command.pattern})${to} queued${id}` : `${command.pattern}${to} queued${id}`);
    state.onSent(record);
  } catch (err) {
    const box = $("confirm-error");
    box.hidden = false;
    box.textContent = err.message;
    // overridable limits: the override box; refused outright (a 422, or a retry's command no
    // longer retryable, a 409 without violations): the same press cannot succeed, Send stays disabled
    const overridable = err.status === 409 && err.detail && Array.isArray(err.detail.violations);
    if (overridable) $("confirm-override-box").hidden = false;
    else if (err.status === 422 || err.status === 409) $("confirm-body").dataset.hard = "1";
    if (err.status === 422 && state.form && !retry) {
      state.form.setErrors(new Map(err.items.filter((i) => i.param).map((i) => [i.param, i.msg])));
    }
    if (err.status === 422 && err.items.some((i) => i.param === "copies")) $("copies-input").setAttribute("aria-invalid", "true");
    if (err.status === 0) notifyError("send", err);
  } finally {
    updateConfirmButton();
  }
}
