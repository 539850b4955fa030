// Keyboard shortcuts (listed in the page: the Shortcuts dialog, and hints on the buttons).
//   Ctrl+Shift+S (or Cmd+Shift+S): SURFACE, exactly one click of the red button per key press
//     (key repeat ignored), with the focus anywhere: a field, the pattern select, a button,
//     any dialog, the 3D view. Why this key: the abort must be one key that always works and
//     never means anything else. Shift+S alone types a capital S in a text field (the script
//     name, the log filter, the token) and picks "surface" in a select, so it would surface or
//     not depending on where the focus happens to be, which an operator at sea cannot be
//     asked to check. With Ctrl held no control types or picks anything, so the key is
//     caught before any control sees it and the form never changes. The confirm dialog of a
//     pending send is cancelled: SURFACE supersedes it.
//   Ctrl+Enter (or Cmd+Enter): Send…, i.e. opens the confirm dialog; it never sends by itself.
//   ?: the list of shortcuts.
// The actions are the buttons' own clicks, so without the operator token (buttons disabled,
// see ui.js applyAuth) they do nothing.

import { $ } from "./ui.js";

/** Focus in a control that takes typing: the page's shortcuts (but send and surface) stay out of
 * its way. */
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

/** Ctrl+Shift+S or Cmd+Shift+S: the letter S, or the S key of a layout whose letters are not
 * Latin (where event.key is another letter). */
function isSurfaceKey(event) {
  if (!event.shiftKey || event.altKey || !(event.ctrlKey || event.metaKey)) return false;
  const key = event.key || "";
  if (key === "S" || key === "s") return true;
  return event.code === "KeyS" && !/^[A-Za-z]$/.test(key);
}

/** The Surface key, caught first (capture on the window, before any control or widget): the
 * form never changes, and nothing on the page can keep it from SURFACE. */
export function onSurfaceKey(event) {
  if (!isSurfaceKey(event)) return;
  event.preventDefault();
  event.stopPropagation();
  if (event.repeat) return; // held down: still one SURFACE
  const button = $("surface-button");
  if (!button || button.disabled || button.hidden) return;
  const confirm = $("confirm-dialog");
  if (confirm && confirm.open) confirm.close(); // the pending send is superseded
  button.click();
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
  if (key === "?" && !event.ctrlKey && !event.metaKey && !event.altKey) {
    if (anyDialogOpen()) return;
    event.preventDefault();
    $("shortcuts-dialog").showModal();
  }
}

export function initShortcuts() {
  window.addEventListener("keydown", onSurfaceKey, true);
  document.addEventListener("keydown", onKey);
  // the 3D view is a same-origin iframe: its key presses do not reach this window
  const viewer = $("viewer");
  if (viewer) {
    viewer.addEventListener("load", () => {
      try {
        viewer.contentWindow.addEventListener("keydown", onSurfaceKey, true);
      } catch {
        // another origin (a viewer_url elsewhere): the key works everywhere but in it
      }
    });
  }
  $("shortcuts-button").addEventListener("click", () => $("shortcuts-dialog").showModal());
}
