// The /ws websocket: telemetry, command, vehicle and link messages, reconnect with backoff.
// Its state is the page's connection to the console ("console" in the header), not the
// vehicle link (link.js).

import { tokenValue } from "./api.js";
import { $, notify } from "./ui.js";

const MIN_DELAY_MS = 500;
const MAX_DELAY_MS = 10000;

/** handlers: {telemetry, fleet_telemetry, command, vehicle, link, ..., open, close}: each gets the
 *  parsed message of its type. */
export function connectLive(handlers) {
  let socket = null;
  let delay = MIN_DELAY_MS;
  let retryTimer = null;
  let countdown = null;

  function setConn(text, cls) {
    const node = $("conn-state");
    node.textContent = text;
    node.className = cls;
  }

  function open() {
    clearTimeout(retryTimer);
    clearInterval(countdown);
    const scheme = window.location.protocol === "https:" ? "wss" : "ws";
    setConn("connecting…", "conn-off");
    try {
      socket = new WebSocket(`${scheme}://${window.location.host}/ws`);
    } catch {
      scheduleRetry();
      return;
    }
    socket.addEventListener("open", () => {
      delay = MIN_DELAY_MS;
      setConn("connected", "conn-on");
      const token = tokenValue();
      if (token) socket.send(JSON.stringify({ type: "auth", token }));
      call("open");
    });
    socket.addEventListener("message", (event) => {
      let msg;
      try {
        msg = JSON.parse(event.data);
      } catch {
        return;
      }
      if (msg && msg.type === "error") notify(`console connection: ${msg.detail || "error"}`, "warn");
      else if (msg && msg.type) call(msg.type, msg);
    });
    socket.addEventListener("close", () => {
      socket = null;
      call("close");
      scheduleRetry();
    });
    socket.addEventListener("error", () => {
      // "close" follows and schedules the retry
    });
  }

  function scheduleRetry() {
    let left = Math.round(delay / 1000);
    setConn(`reconnecting${left ? ` in ${left} s` : "…"}`, "conn-off");
    countdown = setInterval(() => {
      left = Math.max(0, left - 1);
      setConn(`reconnecting${left ? ` in ${left} s` : "…"}`, "conn-off");
    }, 1000);
    retryTimer = setTimeout(open, delay);
    delay = Math.min(MAX_DELAY_MS, delay * 2);
  }

  function call(type, msg) {
    const fn = handlers[type];
    if (!fn) return;
    try {
      fn(msg);
    } catch (err) {
      console.warn(`handler for ${type} failed`, err);
    }
  }

  open();
  return {
    /** Send a control message if the socket is open; true when it went out. */
    send(msg) {
      if (!socket || socket.readyState !== WebSocket.OPEN) return false;
      socket.send(JSON.stringify(msg));
      return true;
    },
    /** Re-authenticate after the token changed. */
    auth() {
      const token = tokenValue();
      if (token && socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({ type: "auth", token }));
    },
    isOpen() {
      return Boolean(socket && socket.readyState === WebSocket.OPEN);
    },
  };
}
