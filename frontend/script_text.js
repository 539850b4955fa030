// The script panel's texts, as the API words them (backend/scripts/labels.py): the page
// shows them and decides nothing itself.

/** A preview timeline event, as the API labels it ("at 30 s from the run's start: ..."). */
export function timelineText(e) {
  if (!e || typeof e !== "object") return String(e ?? "");
  return typeof e.label === "string" ? e.label : String(e.text ?? "");
}

/** A run step in words: "2. hover · after the previous step completes · takes 30 s · sent
 * at 40 s from the run's start, acknowledged by the vehicle" (the API's texts). */
export function runStepText(s, i) {
  if (!s || typeof s !== "object") return `${i + 1}. –`;
  const name = String(s.pattern || "").replace(/_/g, " ");
  const to = s.vehicle ? ` to ${s.vehicle}` : ""; // a fleet's: the vehicle it is sent to
  return [`${i + 1}. ${name}${to}`, s.trigger_text, s.takes_text, s.state_text].filter(Boolean).join(" · ");
}
