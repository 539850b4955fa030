// A mission script as a document: its file format and version, the triggers a step may wait
// on, the patterns that never complete, and a saved script read back (checked, with a reason
// when it is refused). script.js edits, stores and runs it.

import { dictionary } from "./form.js";

export const SCRIPT_FORMAT = "nemesys-mission-script";
export const SCRIPT_VERSION = 1;
/** The triggers in the operator's words (backend/scripts/labels.py's TRIGGER_WORDS;
 * tests/backend/scripts/test_labels.py checks they agree). Every time of a script counts from
 * its run's start: a script is written ahead and run at any point of a dive. */
export const TRIGGERS = [
  ["after_previous", "after the previous step completes"],
  ["at", "at a time from the run's start"],
  ["operator", "on the operator's go"],
];

/** Patterns that repeat until retasked, so never complete: the planner's REPEATING_PATTERNS
 * (backend/scripts/completion.py; tests/backend/scripts/test_completion.py checks they agree). */
export const REPEATING = new Set(["square", "circle"]);

/** Why step i may not wait for the previous step to complete, or null (same text as the API). */
export function completionRefusal(list, i) {
  const step = list[i];
  const prev = i > 0 ? list[i - 1] : null;
  if (!step || !prev || step.trigger.kind !== "after_previous" || !REPEATING.has(prev.pattern)) return null;
  const name = prev.pattern.replace(/_/g, " ");
  return `step ${i + 1} waits for step ${i} (${name}) to complete, but a ${name} repeats until retasked, so it never completes: use a time ('at') or the operator's go`;
}

/** Parse a saved script; throws Error with a reason. */
export function parseScript(text) {
  let doc;
  try {
    doc = JSON.parse(text);
  } catch {
    throw new Error("not JSON");
  }
  if (!doc || typeof doc !== "object" || doc.format !== SCRIPT_FORMAT) throw new Error(`not a ${SCRIPT_FORMAT} file`);
  if (doc.version !== SCRIPT_VERSION) throw new Error(`version ${doc.version} is not supported (expected ${SCRIPT_VERSION})`);
  if (!Array.isArray(doc.steps)) throw new Error("steps must be a list");
  const out = doc.steps.map((s, i) => {
    if (!s || !dictionary.byName.has(s.pattern)) throw new Error(`step ${i + 1}: unknown pattern ${s && s.pattern}`);
    const kind = s.trigger && s.trigger.kind;
    if (!TRIGGERS.some(([k]) => k === kind)) throw new Error(`step ${i + 1}: unknown trigger ${kind}`);
    if (s.params != null && (typeof s.params !== "object" || Array.isArray(s.params))) throw new Error(`step ${i + 1}: params must be an object`);
    const step = { pattern: s.pattern, params: { ...(s.params || {}) }, trigger: { kind, t_s: kind === "at" ? Number(s.trigger.t_s) || 0 : null } };
    if (s.vehicle !== undefined && s.vehicle !== null) step.vehicle = String(s.vehicle); // a fleet's: the console checks it
    return step;
  });
  return { name: String(doc.name || "mission").slice(0, 80), steps: out };
}

/** A trigger in the operator's words ("at 60 s from the run's start"). */
export function triggerText(t) {
  if (!t || typeof t !== "object") return "";
  if (t.kind === "at") return `at ${Number(t.t_s ?? 0)} s from the run's start`;
  const known = TRIGGERS.find(([k]) => k === t.kind);
  return known ? known[1] : "";
}
