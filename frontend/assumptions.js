// The link assumptions form in the status panel: the bit-error rate the station assumes of a
// real link, the delivery probability the copies aim for, and what the copies follow there
// (the assumed BER or the upper end of the estimate from the acknowledgements) (PUT /api/link).
// Values outside their interval are refused in the page, naming the field and the interval,
// and never clamped; the backend's own 422 / 409 message is shown next to its field.

import { api } from "./api.js";
import { berText } from "./delivery.js";
import { currentLink, onLinkChange, renderLink } from "./link.js";
import { $, canWrite, READ_ONLY_TIP } from "./ui.js";

const DEFAULT_TARGET = "0.999"; // the console's default, until the link object says

// by API field: its input and error nodes, the operator's words, its interval and its test
const FIELDS = {
  link_ber: {
    input: "link-ber-input", error: "link-ber-error", label: "assumed bit-error rate",
    interval: "[0, 0.5)", ok: (v) => v >= 0 && v < 0.5,
  },
  delivery_target: {
    input: "delivery-target-input", error: "delivery-target-error", label: "delivery target",
    interval: "(0, 1)", ok: (v) => v > 0 && v < 1,
  },
};

// what the copies follow: sent only when the operator picked another than the console's
const COPIES_FROM = { input: "copies-from-input", error: "copies-from-error", label: "copies follow" };

let training = false;
let busy = false;
let copiesPicked = false; // the operator changed the choice since the console last said

export function initAssumptions() {
  $("link-form").addEventListener("submit", (e) => {
    e.preventDefault();
    apply();
  });
  for (const name of Object.keys(FIELDS)) {
    $(FIELDS[name].input).addEventListener("input", () => showError(name, ""));
  }
  $("delivery-target-input").placeholder = DEFAULT_TARGET;
  $(COPIES_FROM.input).addEventListener("change", () => {
    copiesPicked = true;
    showCopiesError("");
  });
  onLinkChange(updateBerPlaceholder);
  updateBerPlaceholder();
}

/** The console's choice (what the copies follow on a real link), "assumed" until it says. */
function consoleCopiesFrom() {
  const link = currentLink();
  return link && typeof link.copies_from === "string" ? link.copies_from : "assumed";
}

function showCopiesError(text) {
  const node = $(COPIES_FROM.error);
  node.textContent = text;
  node.hidden = !text;
}

/** The session's mode: in training the copies follow the emulated channel's BER. */
let shownMode; // the mode the details' open state was last set for (the operator may toggle it)

export function setAssumptionsMode(mode) {
  training = mode === "training";
  // open on a real link (the copies follow these assumptions), closed in training, where the
  // channel sets the BER: room for the command list on a laptop's screen
  if (mode && mode !== shownMode) {
    shownMode = mode;
    $("link-details").open = !training;
  }
  const input = $("link-ber-input");
  input.disabled = training;
  input.title = training ? "in training the emulated channel's bit-error rate is used (Training panel)" : "";
  $("link-ber-note").hidden = !training;
  if (training) showError("link_ber", "");
  const copies = $(COPIES_FROM.input);
  copies.disabled = training;
  $("copies-from-note").hidden = !training;
  if (training) {
    copiesPicked = false;
    showCopiesError("");
  }
  updateBerPlaceholder();
}

function updateBerPlaceholder() {
  const link = currentLink();
  const ber = link && Number.isFinite(link.ber) ? link.ber : null;
  // the number itself, as the field would take it; the title says it in the link row's words
  const input = $("link-ber-input");
  input.placeholder = ber === null ? "" : String(ber);
  if (link && Number.isFinite(link.delivery_target)) {
    $("delivery-target-input").placeholder = String(link.delivery_target); // as set, never rounded
  }
  if (!training) input.title = ber === null ? "" : `assumed now: BER ${berText(ber)}; empty: unchanged`;
  if (!copiesPicked) $(COPIES_FROM.input).value = training ? "assumed" : consoleCopiesFrom();
}

function showError(name, text) {
  const node = $(FIELDS[name].error);
  node.textContent = text;
  node.hidden = !text;
  const input = $(FIELDS[name].input);
  if (text) input.setAttribute("aria-invalid", "true");
  else input.removeAttribute("aria-invalid");
}

function showResult(text, error = false) {
  const node = $("link-apply-result");
  node.textContent = text;
  node.className = error ? "error" : "hint";
  node.hidden = !text;
}

/** {value: number | null (empty: unchanged)} or {error} for one field. */
function readField(name) {
  const f = FIELDS[name];
  const input = $(f.input);
  const text = input.value.trim();
  if (text === "" && !input.validity.badInput) return { value: null };
  const v = Number(text);
  if (text === "" || !Number.isFinite(v) || !f.ok(v)) {
    const got = text === "" ? "not a number" : `got ${text}`;
    return { error: `${f.label}: ${name} must be a number in ${f.interval}, ${got}` };
  }
  return { value: v };
}

/** The body to send, or null after showing why there is none. */
function readBody() {
  const body = {};
  let bad = false;
  for (const name of Object.keys(FIELDS)) {
    if (name === "link_ber" && training) continue;
    const { value, error } = readField(name);
    showError(name, error || "");
    if (error) bad = true;
    else if (value !== null) body[name] = value;
  }
  if (bad) return null; // the last result still holds: nothing was sent
  const copiesFrom = $(COPIES_FROM.input).value;
  if (!training && copiesFrom !== consoleCopiesFrom()) body.copies_from = copiesFrom;
  if (!Object.keys(body).length) {
    showResult(training ? "enter a delivery target" : "enter an assumed bit-error rate, a delivery target or what the copies follow", true);
    return null;
  }
  return body;
}

function copiesLine(link) {
  const copies = Number.isFinite(link && link.copies) ? link.copies : "unknown";
  const surface = link && Number.isFinite(link.surface_copies) ? link.surface_copies : "until acknowledged";
  return `copies per command now: ${copies} (surface: ${surface})`;
}

function stripPrefix(msg) {
  return String(msg).replace(/^Value error,\s*/, "");
}

/** A refusal from the backend, next to the field it names (a 409 is about link_ber). */
function showRefusal(err) {
  const items = err && typeof err.status === "number" && (err.status === 422 || err.status === 409) ? err.items : [];
  let placed = false;
  for (const { param, msg } of items) {
    if (param === "copies_from") {
      showCopiesError(`${COPIES_FROM.label}: ${stripPrefix(msg)}`);
      placed = true;
      continue;
    }
    const name = Object.hasOwn(FIELDS, param) ? param : err.status === 409 ? "link_ber" : null;
    if (!name) continue;
    showError(name, `${FIELDS[name].label}: ${stripPrefix(msg)}`);
    placed = true;
  }
  showResult(placed ? "not applied" : `not applied: ${(err && err.message) || err}`, true);
}

async function apply() {
  if (busy) return;
  if (!canWrite()) {
    showResult(READ_ONLY_TIP, true); // the button is disabled; Enter in a field must not send either
    return;
  }
  const body = readBody();
  if (!body) return;
  busy = true;
  showResult("applying…");
  try {
    const link = await api("/api/link", { method: "PUT", body });
    if ("delivery_target" in body) $("delivery-target-input").placeholder = String(body.delivery_target); // as set, never rounded
    if ("copies_from" in body) copiesPicked = false; // the console's answer says it from now on
    if (link && typeof link === "object") renderLink(link);
    showResult(copiesLine(link));
  } catch (err) {
    if (err && err.name === "AbortError") return;
    showRefusal(err);
  } finally {
    busy = false;
  }
}
