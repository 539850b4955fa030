// How many copies of a command go out: empty = the console chooses from the link's bit-error
// rate (shown as the placeholder), or the operator's own count (1-20).

import { pct, berText } from "./delivery.js";
import { autoCopies, currentLink, linkAcknowledges, onLinkChange } from "./link.js";
import { $, el } from "./ui.js";

export const MIN_COPIES = 1;
export const MAX_COPIES = 20;

export function initCopies() {
  const input = $("copies-input");
  input.addEventListener("input", () => input.removeAttribute("aria-invalid"));
  onLinkChange(updatePlaceholder);
  updatePlaceholder();
}

function updatePlaceholder() {
  const n = autoCopies();
  $("copies-input").placeholder = n === null ? "auto" : `auto (${n})`;
  const link = currentLink();
  const ber = link && Number.isFinite(link.ber) ? ` (BER ${berText(link.ber)})` : "";
  $("copies-hint").textContent = `empty: the console chooses from the link's bit-error rate${ber}`;
}

/** {copies: null (auto) | 1..20} or {error} when the field holds something else. */
export function readCopies() {
  const input = $("copies-input");
  const text = input.value.trim();
  if (text === "" && input.validity.valid) return { copies: null };
  const n = Number(text);
  if (text === "" || !Number.isInteger(n) || n < MIN_COPIES || n > MAX_COPIES) {
    input.setAttribute("aria-invalid", "true");
    return { error: `copies: a whole number from ${MIN_COPIES} to ${MAX_COPIES}, or empty for auto` };
  }
  input.removeAttribute("aria-invalid");
  return { copies: n };
}

/** The confirm dialog's line on copies: count, who chose it, p(delivered) when the preview says. */
export function copiesLine(preview) {
  const { copies, error } = readCopies();
  if (error) return el("p", { class: "error", testid: "confirm-copies" }, error);
  const auto = autoCopies();
  const count = copies ?? auto;
  const who = copies === null ? "auto, chosen by the console" : "set by you";
  const p = preview && Number.isFinite(preview.p_delivered) && copies === null ? `, p(delivered) ${pct(preview.p_delivered)}` : "";
  const acks = linkAcknowledges() === false ? "; this link gives no acknowledgement: every copy is sent" : "";
  const text = count === null ? `copies: ${who}` : `copies: ${count} (${who}${p})`;
  return el("p", { class: "hint", testid: "confirm-copies" }, text + acks);
}
