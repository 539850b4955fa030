// Keyboard shortcuts (listed in the page: the Shortcuts dialog, and hints on the buttons).
//   Ctrl+Enter (or Cmd+Enter): Send…, i.e. opens the confirm dialog; it never sends by itself.
//   Shift+S: SURFACE, exactly one click of the red button per key press (key repeat ignored).
//   ?: the list of shortcuts.
// Only the send key works while typing in a field. The actions are the buttons' own clicks, so
// without the operator token (buttons disabled, see ui.js applyAuth) they do nothing.

import { $ } from "./ui.js";

/** Focus in a control that takes typing: the page's shortcuts (but send) stay out of its way. */
function typing(target) {
  if (!(target instanceof Element)) return false;
  if (target.isContentEditable) return true;
  const tag = target.tagName;
  if (tag === "TEXTAREA" || tag === "SELECT") return true;
  if (tag !== "INPUT") return false;
  return !["button", "checkbox", "radio", "submit", "reset", "range", "color", "file"].includes(target.type);
}

const anyDialogOpen = () => Boolean(document.querySelector("dialog[open]"));

/** The button's own click, only when it could be clicked (enabled, shown). */
function press(id) {
  const button = $(id);
  if (!button || button.disabled || button.hidden) return false;
  button.click();
  return true;
}

export function onKey(event) {
  if (event.defaultPrevented || event.isComposing) return;
  const key = event.key;
  if (key === "Enter" && (event.ctrlKey || event.metaKey) && !event.shiftKey && !event.altKey) {
    event.preventDefault();
    if (event.repeat || anyDialogOpen()) return;
    press("send-button"); // opens the confirm dialog
    return;
  }
  if (typing(event.target)) return;
  if ((key === "S" || key === "s") && event.shiftKey && !event.ctrlKey && !event.metaKey && !event.altKey) {
    event.preventDefault();
    if (event.repeat) return; // held down: still one SURFACE
    press("surface-button");
    return;
  }
  if (key === "?" && !event.ctrlKey && !event.metaKey && !event.altKey) {
    if (anyDialogOpen()) return;
    event.preventDefault();
    $("shortcuts-dialog").showModal();
  }
}

export function initShortcuts() {
  document.addEventListener("keydown", onKey);
  $("shortcuts-button").addEventListener("click", () => $("shortcuts-dialog").showModal());
}
