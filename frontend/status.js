// The vehicle status panel: latest telemetry wins; the age ticks locally between messages.

import { currentLink, renderLink, setRadio } from "./link.js";
import { $, num, withUnit, latLon } from "./ui.js";

const STALE_S = 5;
const LOW_BATTERY_PCT = 20;
let ageAt = null; // {age, received: performance.now()} of the last telemetry

/** The first finite number of the candidates; "unknown" (null, NaN, missing) otherwise. */
function known(...values) {
  return values.find((v) => typeof v === "number" && Number.isFinite(v)) ?? null;
}

function shown(value, unit, digits) {
  return value === null ? "unknown" : withUnit(value, unit, digits);
}

function set(id, text, cls) {
  const node = $(id);
  node.textContent = text;
  if (cls !== undefined) node.className = cls;
}

/** A telemetry message or GET /api/vehicle: {pose, status, age_s, link?}. Any number may be
 * null (the vehicle did not know it): it is shown as "unknown", never NaN. */
export function renderTelemetry(msg) {
  if (!msg) return;
  const s = msg.status || {};
  const p = msg.pose || {};
  if (msg.status || msg.pose) {
    set("status-depth", shown(known(s.depth_m, p.z_m, p.depth_m), "m", 2));
    set("status-heading", shown(known(s.heading_deg, p.heading_deg), "deg", 1));
    set("status-speed", shown(known(s.speed_mps, p.speed_mps), "m/s", 2));
    const battery = known(s.battery_pct);
    const low = battery !== null && battery < LOW_BATTERY_PCT;
    set("status-battery", battery === null ? "unknown" : `${num(battery, 1)} %${low ? " LOW" : ""}`, low ? "warn-text" : "");
    $("status-battery").title = low ? `below ${LOW_BATTERY_PCT} %: surface soon` : "";
    const mode = typeof s.mode === "string" && s.mode ? s.mode : null;
    set("status-mode", mode || "unknown", `mode-${mode || "unknown"}`);
    const pattern = [s.pattern, msg.active && msg.active.pattern].find((v) => typeof v === "string" && v);
    set("status-pattern", pattern || "none");
    const x = known(s.x_m, p.x_m);
    const y = known(s.y_m, p.y_m);
    set("status-position", x === null && y === null ? "unknown"
      : `x ${x === null ? "unknown" : `${num(x, 1)} m`} north, y ${y === null ? "unknown" : `${num(y, 1)} m`} east`);
    // latitude/longitude as the API computed them (backend/chart/geo.py): null without a datum
    const lat = known(p.lat_deg, s.lat_deg);
    const lon = known(p.lon_deg, s.lon_deg);
    const geo = latLon(lat, lon);
    set("status-latlon", geo === "–" ? (x === null || y === null ? "–" : "no datum: lat/lon unknown") : geo);
    setRadio(s.link);
  }
  if (msg.link && typeof msg.link === "object") renderLink(msg.link);
  // a console without a transmitter (target relay): read from that console's track in the log
  const via = msg.relayed_via || (msg.link && msg.link.relay && msg.link.relay.telemetry_via) || null;
  if (msg.age_s !== undefined && msg.age_s !== null) ageAt = { age: Number(msg.age_s) || 0, received: performance.now(), via };
  tickAge();
}

/** The datum (lat/lon of the north/east origin) from /api/session; null: none set. */
export function renderDatum(datum) {
  const text = datum ? latLon(datum.lat_deg, datum.lon_deg) : "–";
  set("status-datum", datum ? text : "none set (no lat/lon)");
  $("status-datum").title = datum ? `north/east 0 m is at ${text}` : "no datum: set one in the settings or from the surface GPS";
}

export function tickAge() {
  const stale = $("status-stale");
  if (!ageAt) {
    const link = currentLink();
    const none = link && link.capability === "none"; // a modem: no telemetry will ever come
    set("status-age", none ? "none on this link (one-way)" : "no data yet", none ? "" : "warn-text");
    stale.hidden = true;
    return;
  }
  const age = ageAt.age + (performance.now() - ageAt.received) / 1000;
  const old = age > STALE_S;
  const via = ageAt.via ? ` (telemetry via ${ageAt.via}'s log)` : "";
  set("status-age", `${age.toFixed(1)} s ago${via}`, old ? "warn-text" : "");
  stale.hidden = !old;
  if (old) stale.textContent = `Stale: no vehicle message${via} for ${num(age, 0)} s (last known values shown).`;
}

export function startAgeTicker() {
  tickAge();
  return setInterval(tickAge, 500);
}
