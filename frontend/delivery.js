// How a command went out: copies, p(delivered), BER, and one sentence per command state.
// Shared by the command list, the SURFACE banner and the mission log.

import { num } from "./ui.js";

/** Terminal states the operator may retry (POST /api/commands/{id}/retry). */
export const RETRYABLE = new Set(["interrupted", "timed_out", "failed", "rejected", "superseded"]);

const finite = (v) => typeof v === "number" && Number.isFinite(v);

/** 0.99951 -> "99.95 %": enough decimals that a value below 1 never shows as 100 %. */
export function pct(p) {
  if (!finite(p)) return "unknown";
  if (p >= 1) return "100 %";
  if (p <= 0) return "0 %";
  let digits = 2;
  while (digits < 6 && Number((p * 100).toFixed(digits)) >= 100) digits++;
  if (Number((p * 100).toFixed(digits)) >= 100) return `> ${(100 - 10 ** -digits).toFixed(digits)} %`;
  return `${Number((p * 100).toFixed(digits))} %`;
}

/** 0.001 -> "1e-3", 2.5e-4 -> "2.5e-4", 0 -> "0". */
export function berText(ber) {
  if (!finite(ber)) return "unknown";
  if (ber === 0) return "0";
  return ber.toExponential(2).replace(/\.?0+e/, "e").replace("e+", "e");
}

/** "2/3 copies", "4 copies" (no planned count: repeated until acknowledged), or "". */
export function copiesText(r) {
  if (!r || !finite(r.copies_sent)) return "";
  if (finite(r.copies)) return `${r.copies_sent}/${r.copies} cop${r.copies === 1 ? "y" : "ies"}`;
  return copiesWord(r.copies_sent);
}

function copiesWord(n) {
  return n === 1 ? "1 copy" : `${n} copies`;
}

/** "p(delivered) 99.95 % at BER 1e-3", or "" when the record does not say. */
export function deliveryText(r) {
  if (!r || !finite(r.p_delivered)) return "";
  return `p(delivered) ${pct(r.p_delivered)}${finite(r.ber) ? ` at BER ${berText(r.ber)}` : ""}`;
}

/** "copy k of n" while copies of a one-way command go out ("" when unknown). */
export function progressText(r) {
  if (!r || !finite(r.copies_sent)) return "";
  if (finite(r.copies)) return r.copies_sent > 0 ? `copy ${r.copies_sent} of ${r.copies}` : `sending ${copiesWord(r.copies)}`;
  return r.copies_sent > 0 ? `copy ${r.copies_sent}` : "";
}

/** One sentence on the state of a command beyond its badge ("" when there is nothing to add). */
export function stateText(r) {
  const sent = finite(r.copies_sent) ? r.copies_sent : null;
  switch (r.state) {
    case "sent": {
      const n = sent ?? r.copies;
      const p = deliveryText(r);
      return `sent ${finite(n) ? copiesWord(n) : "all copies"}${p ? `, ${p}` : ""} (no acknowledgement on this link)`;
    }
    case "superseded": {
      const by = r.superseded_by != null ? `#${r.superseded_by}` : "a newer command";
      const of = sent === null ? "" : finite(r.copies) ? ` after ${sent} of ${r.copies} copies` : ` after ${copiesWord(sent)}`;
      return `superseded by ${by}${of}`;
    }
    case "interrupted":
      return r.reason || "interrupted (the console stopped or the vehicle was reset)";
    case "transmitted": {
      const progress = progressText(r);
      if (r.two_way === false) return progress ? `${progress}… (no acknowledgement on this link)` : "sending (no acknowledgement on this link)";
      if (finite(r.copies)) return r.copies > 1 ? `${copiesText(r)} sent, waiting for acknowledgement` : "waiting for acknowledgement";
      return `${progress ? `${progress}, ` : ""}repeating until acknowledged`;
    }
    case "timed_out":
      return `no acknowledgement (frame lost or out of range?)${sent && sent > 1 ? ` after ${copiesWord(sent)}` : ""}`;
    default:
      return "";
  }
}

/** An age of the link facts for people: "never" for null, "unknown" for NaN. */
export function age(seconds) {
  if (seconds === null || seconds === undefined) return "never";
  return finite(seconds) ? `${num(seconds, 1)} s ago` : "unknown";
}
