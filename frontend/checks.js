// The checks a send runs (backend/commands/checks.py), as the preview reports them: one line per check
// (ok, violated, or skipped with the reason) and the violations by kind. Hard: no override
// sends it (the depth rating); soft: only with the confirm dialog's override checkbox.

import { el } from "./ui.js";

const CHECK_LABELS = {
  depth_rating: "depth rating",
  depth_limit: "maximum depth",
  speed_limit: "maximum speed",
  turn_radius: "turn radius",
  top_speed: "top speed",
  endurance: "endurance (battery now)",
  geofence: "geofence",
  reach: "link reach",
};

function checkLabel(check) {
  return CHECK_LABELS[check] || String(check).replace(/_/g, " ");
}

function linesOf(preview) {
  return Array.isArray(preview.checks) ? preview.checks : [];
}

/** Hard: no override can send it; soft: the override checkbox can. */
export function isHard(v) {
  return v.kind ? v.kind === "hard" : v.overridable === false;
}

export function kindText(hard) {
  return hard ? "hard: cannot be sent" : "soft: needs the override";
}

/** No violation: how many checks passed and how many could not run. */
export function withinLimits(preview) {
  const lines = linesOf(preview);
  if (!lines.length) return "within limits";
  const ok = lines.filter((c) => c.status === "ok").length;
  const skipped = lines.length - ok;
  return `within limits (${ok} checks ok${skipped ? `, ${skipped} skipped` : ""})`;
}

/** Why the skipped checks could not run, one a line (a tooltip). */
export function skippedTitle(preview) {
  return linesOf(preview).filter((c) => c.status === "skipped")
    .map((c) => `${checkLabel(c.check)} skipped: ${c.detail}`).join("\n");
}

/** One line per check: its status and what it found (a violated one: every violation it
 *  found, with its kind and the allowed range), or why it could not run. */
function checkItems(preview, violations) {
  return linesOf(preview).map((line) => {
    const found = violations.filter((v) => v.check === line.check);
    const hard = found.some(isHard);
    const cls = line.status === "ok" ? "ok" : line.status === "skipped" ? "skipped" : hard ? "error" : "warn";
    const text = found.length ? found.map((v) => `${v.message}${v.allowed ? ` (allowed: ${v.allowed})` : ""}`).join("; ") : line.detail;
    const kind = found.length ? (hard ? "hard" : "soft") : "none";
    return el("li", { class: cls, dataset: { check: line.check, status: line.status, kind } },
      el("strong", {}, `${checkLabel(line.check)}: ${line.status}`),
      found.length ? ` [${kindText(hard)}]` : "",
      ` ${text}`);
  });
}

/** For the confirm dialog: a summary (how many ok, violated, skipped; the violations by kind)
 *  and every check's line. */
export function confirmChecks(preview, violations) {
  const lines = linesOf(preview);
  const count = (status) => lines.filter((c) => c.status === status).length;
  const hard = violations.filter(isHard).length;
  const soft = violations.length - hard;
  const verdict = !violations.length ? "within limits"
    : [hard ? `${hard} hard (cannot be sent)` : "", soft ? `${soft} soft (needs the override)` : ""].filter(Boolean).join(", ");
  return [
    el("p", { class: "checks-summary", testid: "confirm-checks-summary", dataset: { hard: String(hard), soft: String(soft) } },
      `${lines.length} checks: ${count("ok")} ok, ${count("violated")} violated, ${count("skipped")} skipped; ${verdict}`),
    el("ul", { class: "violations checks", testid: "confirm-checks" }, ...checkItems(preview, violations)),
  ];
}
