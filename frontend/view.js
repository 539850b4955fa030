// This page's own 3D view: its iframe's address (with the page's view id) and the
// "Clear replay" button (DELETE /api/replay clears this page's view only).

import { api, withView } from "./api.js";
import { $, notify, notifyError } from "./ui.js";

/**
 * The viewer's address for this page: its websocket URL names this page's view; the viewer
 * runs on its own port; if it names a loopback host, use the host this page came from.
 */
export function viewerSrc(url) {
  const own = withView(url);
  try {
    const u = new URL(own, window.location.href);
    const loopback = ["127.0.0.1", "localhost", "0.0.0.0", "[::1]"];
    if (loopback.includes(u.hostname) && !loopback.includes(window.location.hostname)) u.hostname = window.location.hostname;
    return u.href;
  } catch {
    return own;
  }
}

async function clearReplay() {
  try {
    const r = await api("/api/replay", { method: "DELETE" });
    notify(r && r.cleared ? "replay cleared from this page's 3D view" : "no replay shown in this page's 3D view");
  } catch (err) {
    notifyError("clear replay", err);
  }
}

export function initView() {
  const button = $("clear-replay");
  if (button) button.addEventListener("click", clearReplay);
}
