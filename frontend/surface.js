// The SURFACE abort: the button, and the banner. The banner shows the console's belief of the
// newest Surface (belief.surface: from its record's state only), nothing it works out itself:
// "surfacing…" exactly while that record is on its way. Between a press and the console's
// answer it says the press is being sent; once the answer names a record, the banner waits for
// a belief that knows that record (a belief is pushed on every change of a record's state), so a
// late or out-of-order answer cannot leave it behind. The banner promises acknowledgement only
// on a link that gives one. With a fleet the button is Surface all (one frame to address 0):
// each vehicle's row shows its own Surface, and the banner sums them up (fleet-rows.js).

import { api, ApiError } from "./api.js";
import { currentBelief } from "./belief.js";
import { progressText, deliveryText } from "./delivery.js";
import { fleetOn } from "./fleet.js";
import { linkAcknowledges, autoSurfaceCopies, onLinkChange } from "./link.js";
import { $, emit, notify, notifyError, setTip, on } from "./ui.js";

// How long an ended Surface stays in the banner (s since its record last changed).
const SHOWN_S = { acknowledged: 15, sent: 60, superseded: 60 };
const ERROR_SHOWN_S = 300;

let pressed = null; // a press the console has not answered: {id: null} until it names a record
let clearTimer = null;
let onRecord = () => {};
let sendOverWs = null;

/** wsSurface(): send SURFACE over the websocket (REST down); record(r): show a record. */
export function initSurface({ wsSurface, record }) {
  sendOverWs = wsSurface;
  onRecord = record;
  $("surface-button").addEventListener("click", surface);
  onLinkChange(updateButtonTip);
  on("fleet", updateButtonTip); // Surface all from now on
  updateButtonTip();
  on("belief", ({ belief }) => render(belief));
}

function updateButtonTip() {
  const acks = linkAcknowledges();
  const copies = autoSurfaceCopies();
  let tip = fleetOn()
    ? "Abort: SURFACE ALL now, one frame to every vehicle (address 0; Ctrl+Shift+S does the same; each vehicle's own Surface is in its row)"
    : "Abort: send SURFACE now";
  if (acks === true) tip += ", repeated until acknowledged";
  else if (acks === false) tip += `${copies ? ` as ${copies} cop${copies === 1 ? "y" : "ies"}` : " as several copies"} (this link gives no acknowledgement)`;
  setTip($("surface-button"), tip);
}

function pendingText(s) {
  const twoWay = s && typeof s.two_way === "boolean" ? s.two_way : linkAcknowledges();
  if (twoWay === true) return "surfacing... repeating until acknowledged";
  const progress = progressText(s);
  if (twoWay === false) return `surfacing... ${progress || "sending copies"}`;
  return progress ? `surfacing... ${progress}` : "surfacing...";
}

async function surface() {
  if (fleetOn()) {
    await surfaceAll();
    return;
  }
  pressed = { id: null };
  setSurfaceState("surfacing... sending", "pending");
  try {
    const r = await api("/api/surface", { method: "POST" });
    pressed = { id: r && Number.isFinite(r.id) ? r.id : -1 };
    if (r && r.id !== undefined) onRecord(r);
  } catch (err) {
    pressed = null;
    if (err instanceof ApiError && err.status === 0 && sendOverWs && sendOverWs()) {
      notify("REST unreachable: SURFACE sent over the websocket", "warn");
      render(currentBelief()); // the console's next belief shows its record
      return;
    }
    setSurfaceState(`SURFACE NOT SENT: ${err.message}`, "error");
    notifyError("SURFACE failed", err);
    return;
  }
  render(currentBelief());
}

/** Surface all (a fleet): one record per vehicle, each row shows its own (fleet-rows.js). */
async function surfaceAll() {
  emit("surface_all", { phase: "pressed" });
  try {
    const r = await api("/api/surface", { method: "POST", body: { vehicle: "all" } });
    const records = r && Array.isArray(r.commands) ? r.commands : [];
    for (const record of records) onRecord(record);
    emit("surface_all", { phase: "answered", records });
  } catch (err) {
    if (err instanceof ApiError && err.status === 0 && sendOverWs && sendOverWs()) {
      notify("REST unreachable: SURFACE ALL sent over the websocket", "warn");
      emit("surface_all", { phase: "answered", records: [] }); // the beliefs show the records
      return;
    }
    emit("surface_all", { phase: "failed" });
    setSurfaceState(`SURFACE ALL NOT SENT: ${err.message}`, "error");
    notifyError("SURFACE ALL failed", err);
  }
}

/** A belief's newest Surface in words (null: none): {text, kind, shownS} (shownS: how long
 *  after its record last changed it is worth showing, s). */
export function surfaceText(s) {
  if (!s || s.id === null || s.id === undefined) return null;
  if (s.in_progress) return { text: pendingText(s), kind: "pending", shownS: Infinity };
  const reason = s.reason ? `: ${s.reason}` : "";
  let text;
  let kind;
  switch (s.state) {
    case "acknowledged":
      [text, kind] = ["surface acknowledged", "done"];
      break;
    case "sent": {
      const p = deliveryText(s);
      const n = s.copies_sent ?? s.copies;
      [text, kind] = [`surface sent: ${n ?? "all"} cop${n === 1 ? "y" : "ies"}${p ? `, ${p}` : ""} (no acknowledgement on this link)`, "sent"];
      break;
    }
    case "superseded":
      [text, kind] = [`surface superseded by ${s.superseded_by != null ? `#${s.superseded_by}` : "a newer command"}`, "warn"];
      break;
    default:
      [text, kind] = [`surface ${String(s.state).replace("_", " ")}${reason} (press SURFACE again or Retry)`, "error"];
  }
  return { text, kind, shownS: SHOWN_S[s.state] ?? ERROR_SHOWN_S };
}

/** The banner from a belief (null: none yet); with a fleet, fleet-rows.js draws it. */
function render(belief) {
  if (fleetOn()) return;
  const s = belief && belief.surface;
  if (pressed) {
    // the press is answered by a belief that knows its record (or a newer one)
    if (pressed.id === null || !s || s.id === null || s.id < pressed.id) return;
    pressed = null;
  }
  clearTimeout(clearTimer);
  if (!s || s.id === null || s.id === undefined) {
    setSurfaceState("", "");
    return;
  }
  const { text, kind, shownS } = surfaceText(s);
  if (s.in_progress) {
    setSurfaceState(text, kind);
    return;
  }
  const leftMs = (shownS - (Number(s.changed_s) || 0)) * 1000;
  if (leftMs <= 0) {
    setSurfaceState("", "");
    return;
  }
  setSurfaceState(text, kind);
  clearTimer = setTimeout(() => setSurfaceState("", ""), leftMs);
}

export function setSurfaceState(text, kind) {
  const box = $("surface-state");
  box.textContent = text;
  box.hidden = !text;
  box.className = `surface-state ${kind}`;
  box.dataset.kind = kind;
}
