// The mission log: filtered command table, exports, dives and their 3D replay.

import { api } from "./api.js";
import { copiesText, stateText } from "./delivery.js";
import { drawReplay, openReplay } from "./replay.js";
import { dictionary, unitOf } from "./form.js";
import { $, el, clock, withUnit, summarize, notify, notifyError, resolved, applyAuth, debounce } from "./ui.js";

let rows = [];

function filters() {
  const q = new URLSearchParams();
  const pattern = $("log-filter-pattern").value;
  const state = $("log-filter-state").value;
  if (pattern) q.set("pattern", pattern);
  if (state) q.set("state", state);
  return q;
}

function updateExportLinks() {
  const q = filters().toString();
  $("log-export-csv").href = `/api/log.csv${q ? `?${q}` : ""}`;
  $("log-export-json").href = `/api/log.json${q ? `?${q}` : ""}`;
}

export function initLog() {
  const select = $("log-filter-pattern");
  select.append(...dictionary.list.map((p) => el("option", { value: p.name }, p.name)));
  $("log-filters").addEventListener("submit", (e) => {
    e.preventDefault();
    loadLog();
  });
  select.addEventListener("change", loadLog);
  $("log-filter-state").addEventListener("change", loadLog);
  $("log-filter-text").addEventListener("input", debounce(renderRows, 150));
  updateExportLinks();
}

export async function loadLog() {
  updateExportLinks();
  const q = filters();
  q.set("limit", "500");
  try {
    const data = await api(`/api/commands?${q}`);
    rows = Array.isArray(data) ? data : (data && data.commands) || [];
    resolved("mission log");
  } catch (err) {
    notifyError("mission log", err);
    rows = [];
  }
  renderRows();
  loadDives();
}

function paramsText(r) {
  const sent = r.params || {};
  const requested = r.requested || {};
  return Object.keys(sent).map((k) => {
    const unit = unitOf(r.pattern, k);
    const req = requested[k];
    const changed = req !== undefined && String(req) !== String(sent[k]);
    return changed ? `${k} ${withUnit(req, unit)} -> ${withUnit(sent[k], unit)}` : `${k} ${withUnit(sent[k], unit)}`;
  }).join(", ");
}

function outcome(r) {
  if (r.state === "acknowledged" && r.ack) {
    const a = r.ack;
    return `corrected ${a.corrected_bits ?? "?"} bits${a.decode_latency_ms != null ? `, decode ${withUnit(a.decode_latency_ms, "ms")}` : ""}`;
  }
  if (["sent", "superseded", "interrupted"].includes(r.state)) return stateText(r);
  return r.reason || "";
}

/** "2/3 copies (4 frames)": the copies, and the frames handed to the link when they differ. */
function copiesCell(r) {
  const copies = copiesText(r);
  if (!copies) return r.attempts ?? "–";
  return r.attempts != null && r.attempts !== r.copies_sent ? `${copies} (${r.attempts} frames)` : copies;
}

function renderRows() {
  const text = $("log-filter-text").value.trim().toLowerCase();
  const shown = text ? rows.filter((r) => JSON.stringify(r).toLowerCase().includes(text)) : rows;
  const body = $("log-rows");
  if (!shown.length) {
    body.replaceChildren(el("tr", {}, el("td", { colspan: 9, class: "hint" }, rows.length ? "no row matches the text filter" : "no commands")));
    return;
  }
  body.replaceChildren(...shown.map((r) => el("tr", { testid: `log-row-${r.id}` },
    el("td", { title: r.created_at || "" }, clock(r.created_at)),
    el("td", {}, r.dive ?? "–"),
    el("td", {}, r.kind === "surface" ? "SURFACE" : r.pattern || "?"),
    el("td", {}, paramsText(r)),
    el("td", {}, el("span", { class: `state-badge st-${r.state}` }, r.state)),
    el("td", {}, copiesCell(r)),
    el("td", {}, r.operator || "–"),
    el("td", {}, el("code", {}, r.hex || "–")),
    el("td", {}, outcome(r)))));
}

async function loadDives() {
  const list = $("dives-list");
  let dives;
  try {
    const data = await api("/api/dives");
    dives = Array.isArray(data) ? data : (data && data.dives) || [];
    resolved("dives");
  } catch (err) {
    notifyError("dives", err);
    return;
  }
  if (!dives.length) {
    list.replaceChildren(el("li", { class: "hint" }, "no dives yet"));
    return;
  }
  list.replaceChildren(...dives.map((d) => {
    const id = d.id ?? d.dive;
    return el("li", { testid: `dive-${id}` },
      el("strong", {}, `dive ${id}`), " ",
      el("span", { class: "muted" }, [clock(d.started_at), summarize(d, ["id", "dive", "started_at", "ended_at"])].filter((t) => t && t !== "–").join(" · ")),
      " ",
      el("button", { type: "button", class: "small", testid: `replay-${id}`, dataset: { auth: "" }, onclick: () => replay(id) }, "Replay in 3D"));
  }));
  applyAuth(undefined, list);
}

async function replay(id) {
  try {
    const vehicle = await drawReplay(id); // a fleet's: the selected vehicle's
    resolved(`replay of dive ${id}`);
    notify(`dive ${id}${vehicle ? ` of ${vehicle}` : ""} drawn in the 3D view: its time slider is under the view`);
    openReplay(id, vehicle);
  } catch (err) {
    notifyError(`replay of dive ${id}`, err);
  }
}
