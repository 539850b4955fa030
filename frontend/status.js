// The vehicle status panel: latest telemetry wins; the age ticks locally between messages.

import { $, num, withUnit } from "./ui.js";

const STALE_S = 5;
const LOW_BATTERY_PCT = 20;
let ageAt = null; // {age, received: performance.now()} of the last telemetry
let lastLink = null; // the console's own link state (GET /api/vehicle "link"), kept between telemetry

function first(...values) {
  return values.find((v) => v !== undefined && v !== null);
}

function set(id, text, cls) {
  const node = $(id);
  node.textContent = text;
  if (cls !== undefined) node.className = cls;
}

function linkText(status, link) {
  const l = (status && status.link) || (link && typeof link === "object" ? link : {});
  const parts = [];
  if (typeof link === "string") parts.push(link);
  else if (link && typeof link === "object" && (link.state || link.connected !== undefined)) {
    parts.push(link.state || (link.connected ? "connected" : "disconnected"));
  }
  if (l.in_range !== undefined) parts.push(l.in_range ? "in range" : "OUT OF RANGE");
  if (l.distance_m != null) parts.push(`${num(l.distance_m, 1)} m of ${l.range_m == null ? "unlimited" : withUnit(l.range_m, "m", 0)} range`);
  if (l.frames_in != null) parts.push(`frames in ${l.frames_in}, lost ${l.frames_lost ?? 0}`);
  if (l.accepted != null) parts.push(`accepted ${l.accepted}, rejected ${l.rejected ?? 0}`);
  if (l.ber) parts.push(`BER ${l.ber}`);
  return { text: parts.join(" · ") || "–", bad: l.in_range === false || (link && link.connected === false) };
}

/** A telemetry message or GET /api/vehicle: {pose, status, age_s, link?}. */
export function renderTelemetry(msg) {
  if (!msg) return;
  const s = msg.status || {};
  const p = msg.pose || {};
  if (msg.status || msg.pose) {
    set("status-depth", withUnit(first(s.depth_m, p.z_m, p.depth_m), "m", 2));
    set("status-heading", withUnit(first(s.heading_deg, p.heading_deg), "deg", 1));
    set("status-speed", withUnit(first(s.speed_mps, p.speed_mps), "m/s", 2));
    const battery = s.battery_pct;
    const low = battery != null && battery < LOW_BATTERY_PCT;
    set("status-battery", battery == null ? "–" : `${num(battery, 1)} %${low ? " LOW" : ""}`, low ? "warn-text" : "");
    $("status-battery").title = low ? `below ${LOW_BATTERY_PCT} %: surface soon` : "";
    set("status-mode", s.mode || "–", `mode-${s.mode || "unknown"}`);
    set("status-pattern", first(s.pattern, msg.active && msg.active.pattern) || "none");
    const x = first(s.x_m, p.x_m);
    const y = first(s.y_m, p.y_m);
    set("status-position", x == null ? "–" : `x ${num(x, 1)} m north, y ${num(y, 1)} m east`);
  }
  if ("link" in msg) lastLink = msg.link;
  const link = linkText(s, lastLink);
  set("status-link", link.text, link.bad ? "warn-text" : "");
  if (msg.age_s !== undefined) ageAt = { age: Number(msg.age_s) || 0, received: performance.now() };
  tickAge();
}

export function tickAge() {
  const stale = $("status-stale");
  if (!ageAt) {
    set("status-age", "no data yet", "warn-text");
    stale.hidden = true;
    return;
  }
  const age = ageAt.age + (performance.now() - ageAt.received) / 1000;
  const old = age > STALE_S;
  set("status-age", `${age.toFixed(1)} s ago`, old ? "warn-text" : "");
  stale.hidden = !old;
  if (old) stale.textContent = `Stale: no vehicle message for ${num(age, 0)} s (last known values shown).`;
}

export function startAgeTicker() {
  tickAge();
  return setInterval(tickAge, 500);
}
