// The SURFACE abort: the button, and the banner that follows its command to an end state.
// The banner promises acknowledgement only on a link that gives one.

import { api, ApiError } from "./api.js";
import { progressText, deliveryText } from "./delivery.js";
import { linkAcknowledges, autoSurfaceCopies, onLinkChange } from "./link.js";
import { $, notify, notifyError, setTip } from "./ui.js";

let surfaceId = null; // the surface command followed by the banner
let successorOf = null; // the id a followed surface was superseded by (adopted if it is a surface)
let surfaceWaiting = false; // POST /api/surface sent, no record yet
let surfaceClickedAt = 0;
let clearTimer = null;
let onRecord = () => {};
let lookup = () => null;
let sendOverWs = null;

/** wsSurface(): send SURFACE over the websocket (REST down); onRecord(r): show a record;
 * lookup(id): a record already known by id. */
export function initSurface({ wsSurface, record, find }) {
  sendOverWs = wsSurface;
  onRecord = record;
  lookup = find;
  $("surface-button").addEventListener("click", surface);
  onLinkChange(updateButtonTip);
  updateButtonTip();
}

function updateButtonTip() {
  const acks = linkAcknowledges();
  const copies = autoSurfaceCopies();
  let tip = "Abort: send SURFACE now";
  if (acks === true) tip += ", repeated until acknowledged";
  else if (acks === false) tip += `${copies ? ` as ${copies} cop${copies === 1 ? "y" : "ies"}` : " as several copies"} (this link gives no acknowledgement)`;
  setTip($("surface-button"), tip);
}

function pendingText(r) {
  const twoWay = r && typeof r.two_way === "boolean" ? r.two_way : linkAcknowledges();
  if (twoWay === true) return "surfacing... repeating until acknowledged";
  const progress = progressText(r);
  if (twoWay === false) return `surfacing... ${progress || "sending copies"}`;
  return progress ? `surfacing... ${progress}` : "surfacing...";
}

async function surface() {
  setSurfaceState(pendingText(null), "pending");
  surfaceWaiting = true;
  surfaceClickedAt = Date.now();
  try {
    const r = await api("/api/surface", { method: "POST" });
    if (r && r.id !== undefined) {
      follow(r.id);
      onRecord(r);
    }
  } catch (err) {
    if (err instanceof ApiError && err.status === 0 && sendOverWs && sendOverWs()) {
      notify("REST unreachable: SURFACE sent over the websocket", "warn");
      return;
    }
    surfaceWaiting = false;
    setSurfaceState(`SURFACE NOT SENT: ${err.message}`, "error");
    notifyError("SURFACE failed", err);
  }
}

/** Follow a surface command the operator started another way (Retry of a surface). */
export function followSurface(id) {
  follow(id);
  surfaceWaiting = false;
}

function follow(id) {
  surfaceId = id;
  successorOf = null;
}

const isSurface = (r) => Boolean(r) && (r.kind === "surface" || r.pattern === "surface");

/** Every command record passes here; the banner follows the surface the operator pressed. */
export function trackSurface(r) {
  if (!isSurface(r)) return;
  if (successorOf !== null && String(r.id) === successorOf) follow(r.id);
  const created = Date.parse(r.created_at || "");
  const recent = Number.isNaN(created) || created >= surfaceClickedAt - 60000;
  if (surfaceId === null && surfaceWaiting && recent) follow(r.id);
  if (surfaceId === null || String(r.id) !== String(surfaceId)) return;
  surfaceWaiting = false;
  const reason = r.reason ? `: ${r.reason}` : "";
  switch (r.state) {
    case "acknowledged":
      finish("surface acknowledged", "done", 15000);
      break;
    case "sent": {
      const p = deliveryText(r);
      const n = r.copies_sent ?? r.copies;
      finish(`surface sent: ${n ?? "all"} cop${n === 1 ? "y" : "ies"}${p ? `, ${p}` : ""} (no acknowledgement on this link)`, "sent", 60000);
      break;
    }
    case "superseded": {
      const by = r.superseded_by;
      setSurfaceState(`surface superseded by ${by != null ? `#${by}` : "a newer command"}`, "warn");
      if (by != null) {
        const next = lookup(by);
        if (isSurface(next)) {
          follow(next.id);
          trackSurface(next);
        } else if (!next) successorOf = String(by);
      }
      break;
    }
    case "interrupted":
    case "failed":
    case "rejected":
    case "timed_out":
      setSurfaceState(`surface ${r.state.replace("_", " ")}${reason} (press SURFACE again or Retry)`, "error");
      break;
    default:
      setSurfaceState(pendingText(r), "pending");
  }
}

function finish(text, kind, clearMs) {
  const id = surfaceId;
  setSurfaceState(text, kind);
  clearTimeout(clearTimer);
  clearTimer = setTimeout(() => {
    if (surfaceId === id && !surfaceWaiting) {
      surfaceId = null;
      setSurfaceState("", "");
    }
  }, clearMs);
}

function setSurfaceState(text, kind) {
  const box = $("surface-state");
  box.textContent = text;
  box.hidden = !text;
  box.className = `surface-state ${kind}`;
}
