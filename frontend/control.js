// Who is in control of each vehicle (issue 24): consoles sharing one mission log (PostgreSQL)
// hand control of a vehicle to one another by explicit actions, and only the console in control
// sends to it (others get 409 naming who is). The Control panel shows, per vehicle, the console
// and operator in control, since when, the epoch and whether the owner allows a takeover, and
// offers exactly the actions that make sense for this console: Request control (another
// console, or nobody, has it), Release and "allow takeover" (this console has it), Grant /
// Refuse (a request waits for this console's answer), Take over (the owner allows it). Each is
// POST /api/control with the operator token; its answer, or the refusal's own words, is shown
// under the rows. Every word of the rows is the console's (GET /api/control, then the /ws
// "control" messages; the last logged change of each vehicle from the /ws "event" messages);
// the page learns which console it is from /api/session (console.name). On a SQLite log (one
// console, always in control: no send is ever refused for control) the panel is one line that
// says so, without buttons. Surface is never gated here: any console's Surface is accepted.

import { api } from "./api.js";
import { currentLink, onLinkChange } from "./link.js";
import { $, applyAuth, canWrite, clock, el, notifyError, on, resolved } from "./ui.js";

const views = new Map(); // vehicle -> its ControlView (the console's words)
const lastChange = new Map(); // vehicle -> the detail of its last control event seen
let me = null; // /api/session console: {name, shared_log, control_timeout_s}
let reachable = true; // the page's websocket to the console is open
let logReached = true; // the console reaches its mission log's database
let readAt = null; // when the views were last read or told (Date)
let busy = false;

/** Listen to the session (which console this page belongs to) and read who is in control. */
export function initControl() {
  on("session", ({ session }) => {
    const next = session && session.console ? session.console : null;
    const changed = JSON.stringify(next) !== JSON.stringify(me);
    me = next;
    if (changed) render();
  });
  // the console reaches its mission log or not (link.mission_log, the same for every vehicle)
  onLinkChange(() => {
    const reach = currentLink() && currentLink().mission_log;
    setControlLogReached(!(reach && reach.reachable === false));
  });
  loadControl();
}

/** GET /api/control: every vehicle's control (at start and when the page reconnects). */
export async function loadControl() {
  try {
    const list = await api("/api/control");
    resolved("control state"); // not "control": link.js's message row line of a change
    views.clear();
    for (const c of Array.isArray(list) ? list : []) if (c && c.vehicle) views.set(c.vehicle, c);
    readAt = new Date();
  } catch (err) {
    notifyError("control state", err);
  }
  render();
}

/** A /ws "control" message: a vehicle's control after a change (here or on another console). */
export function controlNews(c) {
  if (!c || typeof c !== "object" || !c.vehicle) return;
  views.set(c.vehicle, c);
  readAt = new Date();
  render();
}

/** A /ws "event" message: a control change as the mission log wrote it (kind "control"). */
export function controlEvent(e) {
  if (!e || e.kind !== "control" || !e.data || !e.data.vehicle || !e.detail) return;
  lastChange.set(String(e.data.vehicle), { detail: String(e.detail), at: e.at });
  render();
}

/** The page's websocket open (true) or closed: closed, the rows are what it last heard. */
export function setControlReachable(ok) {
  reachable = ok;
  render();
}

/** The console's mission log reached or not (link.mission_log): unreached, control is as
 *  last read (the console cannot read the log to know better). */
function setControlLogReached(ok) {
  if (logReached === ok) return;
  logReached = ok;
  render();
}

// ---- what a view says, from this console's side ----

function owner(c) {
  return c.console || null;
}

function mine(c) {
  return Boolean(me && owner(c) === me.name);
}

/** "this console, ship (operator alice)", "console shore (operator bob)" or "nobody". */
function whoText(console, operator) {
  if (!console) return "nobody";
  const op = operator ? ` (operator ${operator})` : "";
  return me && console === me.name ? `this console, ${console}${op}` : `console ${console}${op}`;
}

/** A request waiting for this console's answer (this console is in control). */
function askedOfMe(c) {
  return c.request && mine(c) && c.request.console !== me.name ? c.request : null;
}

// ---- the panel ----

function render() {
  const panel = $("control-panel");
  if (!panel) return;
  const solo = Boolean(me && !me.shared_log);
  panel.hidden = !me; // not known yet: nothing claimed
  panel.classList.toggle("solo", solo);
  $("control-title").hidden = solo;
  $("control-solo").hidden = !solo;
  if (solo) {
    renderSolo();
    return;
  }
  const stale = $("control-stale");
  const when = readAt ? ` (read at ${clock(readAt.toISOString())})` : "";
  const why = !reachable
    ? "Console unreachable: who is in control is what the page last heard"
    : !logReached ? "Mission log unreachable: who is in control is as the console last read it" : "";
  stale.hidden = !why;
  stale.textContent = why ? `${why}${when}.` : "";
  $("control-rows").classList.toggle("stale", Boolean(why));
  const rows = [...views.values()].map(row);
  $("control-rows").replaceChildren(...rows);
  applyAuth(canWrite(), $("control-rows"));
}

/** A SQLite log: one line, no buttons (the actions would change nothing a send depends on). */
function renderSolo() {
  const node = $("control-solo");
  node.replaceChildren(el("strong", {}, "Control: "), "this console, the only one on its mission log (SQLite)");
  node.title = `this console (${me.name}) keeps its mission log in a SQLite file that no other ` +
    "console shares: it is always in control of its vehicles, and no send is refused for control";
  $("control-stale").hidden = true;
  $("control-rows").replaceChildren();
  $("control-result").hidden = true;
}

function row(c) {
  const v = c.vehicle;
  const held = mine(c);
  const facts = [];
  if (c.since) facts.push(`${owner(c) ? "since" : "nobody since"} ${clock(c.since)}`);
  facts.push(`epoch ${c.epoch}`);
  if (owner(c)) facts.push(c.takeover_allowed ? "takeover allowed" : "no takeover without asking");
  const lines = [
    el("div", { class: "control-head" },
      el("strong", { class: "control-vehicle" }, v),
      el("span", { class: held ? "control-who mine" : "control-who", testid: `control-who-${v}` },
        whoText(owner(c), c.operator)),
      el("span", { class: "muted control-facts", testid: `control-facts-${v}` }, facts.join(" · "))),
  ];
  const r = c.request;
  if (r) {
    const at = r.at ? ` (${clock(r.at)})` : "";
    const text = askedOfMe(c)
      ? `${whoText(r.console, r.operator)} asks for control${at}: grant or refuse`
      : me && r.console === me.name
        ? `this console's request${at} waits for the answer of ${whoText(owner(c), c.operator)}`
        : `${whoText(r.console, r.operator)} asks ${whoText(owner(c), c.operator)} for control${at}`;
    lines.push(el("div", { class: askedOfMe(c) ? "control-request warn-text" : "control-request", testid: `control-asked-${v}` }, text));
  }
  const buttons = actions(c);
  if (buttons.length) lines.push(el("div", { class: "control-actions" }, ...buttons));
  if (!held && owner(c) && me) {
    lines.push(el("div", { class: "hint control-note", testid: `control-note-${v}` },
      "not in control here: sends are refused (409); SURFACE is accepted from any console"));
  }
  const last = lastChange.get(v);
  if (last) {
    lines.push(el("div", { class: "muted control-last", testid: `control-last-${v}` },
      `logged ${clock(last.at)}: ${last.detail}`));
  }
  return el("li", { class: held ? "control-row mine" : "control-row", testid: `control-row-${v}`, dataset: { vehicle: v } }, ...lines);
}

/** The buttons that make sense for this console now (none when it does not know its name). */
function actions(c) {
  if (!me) return [];
  const v = c.vehicle;
  const out = [];
  const button = (action, label, title) => el("button", {
    type: "button", class: action === "grant" ? "small primary" : "small", testid: `control-${action}-${v}`,
    dataset: { auth: "" }, title, onclick: () => act(action, v),
  }, label);
  if (mine(c)) {
    const asked = askedOfMe(c);
    if (asked) {
      out.push(button("grant", "Grant", `hand control of ${v} to console ${asked.console}: this console's sends to it are refused from then on`));
      out.push(button("refuse", "Refuse", `keep control of ${v}; console ${asked.console} is told`));
    }
    out.push(button("release", "Release", `nobody is in control of ${v} after this: any console may request it (granted at once)`));
    const box = el("input", {
      type: "checkbox", testid: `control-takeover-allowed-${v}`, dataset: { auth: "" }, checked: Boolean(c.takeover_allowed),
      onchange: (e) => act("request", v, { takeover_allowed: e.target.checked }),
    });
    out.push(el("label", { class: "control-allow", title: "another console may take control of this vehicle without asking" }, box, " allow takeover"));
    return out;
  }
  const waiting = c.request && c.request.console === me.name;
  if (!waiting) {
    const title = owner(c)
      ? `ask console ${owner(c)} for control of ${v}: it grants or refuses`
      : `nobody is in control of ${v}: granted at once`;
    out.push(button("request", "Request control", title));
  }
  if (owner(c) && c.takeover_allowed) {
    out.push(button("takeover", "Take over", `console ${owner(c)} allows a takeover: control of ${v} is this console's at once`));
  }
  return out;
}

/** What the answer of an action says, in words. */
function outcomeText(action, v, r) {
  const c = r && r.control;
  const who = c ? whoText(owner(c), c.operator) : "unknown";
  switch (r && r.outcome) {
    case "granted": return action === "grant" ? `${v}: control granted to ${who}` : `${v}: control is this console's`;
    case "pending": return `${v}: request sent; it waits for the answer of ${who}`;
    case "refused": return `${v}: request refused; control stays with ${who}`;
    case "released": return `${v}: control released; nobody is in control`;
    case "taken_over": return `${v}: taken over; control is this console's`;
    case "unchanged":
      return c && "takeover_allowed" in c
        ? `${v}: this console keeps control; takeover ${c.takeover_allowed ? "allowed" : "not allowed"}`
        : `${v}: unchanged`;
    default: return `${v}: ${(r && r.outcome) || "no answer"}`;
  }
}

function showResult(text, error = false) {
  const node = $("control-result");
  node.textContent = text;
  node.className = error ? "error" : "hint";
  node.hidden = !text;
}

/** POST /api/control {action, vehicle, ...extra}: the answer shown, the row updated. */
async function act(action, vehicle, extra = {}) {
  if (busy) return;
  busy = true;
  showResult(`${vehicle}: ${action}…`);
  try {
    const r = await api("/api/control", { method: "POST", body: { action, vehicle, ...extra } });
    if (r && r.control) controlNews(r.control);
    showResult(outcomeText(action, vehicle, r));
  } catch (err) {
    if (err && err.name === "AbortError") return;
    showResult(`${vehicle}: ${action} not done: ${(err && err.message) || err}`, true);
    render(); // a checkbox the console did not follow goes back to what it says
  } finally {
    busy = false;
  }
}
