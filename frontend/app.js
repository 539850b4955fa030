// NemeSys Console page: wires the session, token, live link and the panels together.

import { api, adoptUrlToken, setToken, hasToken } from "./api.js";
import { initAssumptions, setAssumptionsMode } from "./assumptions.js";
import { initAuthoring, current } from "./authoring.js";
import { forgetBelief, renderBelief, setBeliefReachable } from "./belief.js";
import { initCommands, loadCommands, upsertCommand, renderEcho } from "./commands.js";
import { controlEvent, controlNews, initControl, loadControl, setControlReachable } from "./control.js";
import { fleetOn, forSelected, loadFleet, vehiclePath } from "./fleet.js";
import { initFleetChart } from "./fleet-chart.js";
import { fleetNews, fleetVehicle, initFleetRows } from "./fleet-rows.js";
import { setDictionary } from "./form.js";
import { initLinkTest, renderControl, renderLink, renderLogEvent, setConsoleReachable, setSessionLink } from "./link.js";
import { connectLive } from "./live.js";
import { initLog, loadLog } from "./log.js";
import { initChart } from "./chart.js";
import { initPlots } from "./plots.js";
import { initPrediction } from "./prediction.js";
import { initReplay } from "./replay.js";
import { initScript, addStep } from "./script.js";
import { initShortcuts } from "./shortcuts.js";
import { renderDatum, renderTelemetry, startAgeTicker } from "./status.js";
import { initTheme } from "./theme.js";
import { initTraining, loadTraining } from "./training.js";
import { $, notify, notifyError, resolved, applyAuth, debounce, emit, on } from "./ui.js";
import { initView, viewerSrc } from "./view.js"; // this page's own 3D view

const RETRY_MS = 3000;
let session = null;
let live = null;

// ---- session and token ----

function renderSession(s) {
  const mode = s ? s.mode : null;
  const badge = $("mode-badge");
  badge.textContent = mode ? mode.toUpperCase() : "UNKNOWN";
  badge.className = `badge mode-${mode || "unknown"}`;
  $("target").textContent = s ? s.target || "–" : "–";
  $("version").textContent = s && s.version ? `NemeSys Console ${s.version}` : "";
  const viewer = $("viewer");
  if (s && s.viewer_url) {
    const src = viewerSrc(s.viewer_url);
    if (viewer.getAttribute("src") !== src) viewer.src = src;
  }
  $("viewer-missing").hidden = Boolean(s && s.viewer_url);
  viewer.hidden = !(s && s.viewer_url);

  const token = hasToken();
  const rejected = token && s && s.authenticated === false;
  const auth = $("auth-state");
  if (!token) {
    auth.textContent = "read-only (observer)";
    auth.className = "auth-ro";
  } else if (rejected) {
    auth.textContent = "token refused: read-only";
    auth.className = "auth-bad";
  } else {
    // the role, and the operator's name when it is not just "operator" again
    const name = s && s.operator && s.operator !== "operator" ? ` (${s.operator})` : "";
    auth.textContent = `operator${name}`;
    auth.className = "auth-ok";
  }
  if (s && s.link) setSessionLink(s.link);
  if (s && "datum" in s) renderDatum(s.datum);
  if (s) emit("session", { session: s });
  setAssumptionsMode(mode);
  $("token-form").hidden = token && !rejected;
  $("token-clear").hidden = !token;
  const notice = $("auth-notice");
  notice.hidden = !rejected;
  notice.textContent = rejected
    ? "The console refuses this page's operator token (a console restarted with --new-token " +
      "has a new one): this page is read-only. To operate, open the URL with the new token that the " +
      `console printed (${window.location.origin}/?token=…), or paste that token above.`
    : "";
  applyAuth(token && !rejected);
}

/** The console refused the token on (re)connecting /ws: read-only now, not at the next press. */
function tokenRefused() {
  if (!hasToken() || (session && session.authenticated === false)) return;
  if (!session) {
    loadSession(); // not known yet: it says the same
    return;
  }
  session = { ...session, authenticated: false };
  renderSession(session);
}

/** Accepted on (re)connecting: operator again if it had been refused (e.g. a token pasted). */
function tokenAccepted() {
  if (session && session.authenticated === false && hasToken()) loadSession();
}

async function loadSession() {
  try {
    session = await api("/api/session");
    resolved("session");
  } catch (err) {
    notifyError("session", err);
    session = null;
  }
  renderSession(session);
  return session;
}

function initToken() {
  $("token-form").addEventListener("submit", async (e) => {
    e.preventDefault();
    const value = $("token-input").value.trim();
    if (!value) return;
    setToken(value);
    $("token-input").value = "";
    const s = await loadSession();
    if (live) live.auth();
    if (s && s.authenticated === false) notify("403: that token was rejected", "error");
    else if (s) notify("operator token accepted");
  });
  $("token-clear").addEventListener("click", () => {
    setToken("");
    renderSession(session && { ...session, authenticated: false });
    notify("token forgotten: read-only");
  });
}

// ---- vehicle ----

async function loadVehicle() {
  try {
    const path = vehiclePath(); // a fleet: the selected vehicle's
    const v = await api(path);
    if (path !== vehiclePath()) return; // another vehicle was selected meanwhile
    resolved("vehicle state");
    if (fleetOn()) fleetVehicle(v);
    renderTelemetry(v);
    emit("telemetry", { msg: v });
    renderEcho(v);
    renderBelief(v.belief);
  } catch (err) {
    notifyError("vehicle state", err);
  }
}

/** Keep the status fresh over REST while the websocket is down. */
function startVehicleFallback() {
  setInterval(() => {
    if (live && !live.isOpen()) loadVehicle();
  }, 5000);
}

// ---- dictionary-dependent panels ----

async function loadDictionary() {
  for (let attempt = 0; ; attempt++) {
    try {
      const data = await api("/api/dictionary");
      setDictionary(Array.isArray(data) ? data : (data && data.patterns) || []);
      return;
    } catch (err) {
      if (attempt === 0) notifyError("command dictionary (retrying)", err);
      await new Promise((resolve) => setTimeout(resolve, RETRY_MS));
    }
  }
}

/** The columns fill the window below the header, whose height changes when it wraps. */
function trackTopbar() {
  const bar = document.querySelector(".topbar");
  const set = () => document.documentElement.style.setProperty("--topbar-h", `${bar.offsetHeight}px`);
  new ResizeObserver(set).observe(bar);
  set();
}

async function main() {
  trackTopbar();
  initTheme();
  initView();
  initShortcuts();
  // a fleet's rows and chart markers, and the panels that follow the selected vehicle
  initFleetRows();
  initFleetChart();
  on("vehicle_selected", () => {
    forgetBelief();
    loadVehicle();
  });
  // the chart, the prediction and the plots listen to the page events from here on
  initChart().catch((err) => notifyError("chart", err));
  initPrediction();
  initPlots().catch((err) => notifyError("plots", err));
  adoptUrlToken();
  initToken();
  // a fleet: the Surface key and button surface every vehicle
  const surfaceMsg = () => (fleetOn() ? { type: "surface", vehicle: "all" } : { type: "surface" });
  initCommands({ wsSurface: () => Boolean(live && live.send(surfaceMsg())) });
  initTraining();
  initAssumptions();
  initLinkTest();
  initControl(); // who is in control of each vehicle: the header's word and the Control panel
  startAgeTicker();
  renderSession(null);

  let opened = false;
  const refreshLog = debounce(loadLog, 2000);
  // with a fleet every vehicle's news updates its row; the single-vehicle panels take the
  // selected vehicle's only (forSelected: all of it without a fleet)
  const onTelemetry = (m) => {
    fleetNews("telemetry", m);
    if (!forSelected(m)) return;
    renderTelemetry(m);
    emit("telemetry", { msg: m });
  };
  live = connectLive({
    telemetry: onTelemetry,
    // a fleet's changed vehicles in one message a period: each vehicle's telemetry in turn
    fleet_telemetry: (m) => {
      for (const t of m.telemetry || []) {
        try {
          onTelemetry(t);
        } catch (err) {
          console.warn(`telemetry of ${t && t.vehicle} failed`, err); // the others still shown
        }
      }
    },
    command: (m) => {
      upsertCommand(m.command);
      refreshLog();
      fleetNews("command", m);
    },
    vehicle: (m) => {
      if (!forSelected(m)) return;
      renderEcho(m);
      emit("vehicle", { msg: m });
    },
    link: (m) => {
      fleetNews("link", m);
      if (forSelected(m)) renderLink(m.link);
    },
    control: (m) => { // who is in control (consoles sharing a log): the message row, the panel
      renderControl(m.control);
      controlNews(m.control);
    },
    event: (m) => { // a mission log event (script.js: a run stopped; a relayed command refused)
      emit("log_event", m.event);
      renderLogEvent(m.event);
      controlEvent(m.event);
    },
    belief: (m) => {
      fleetNews("belief", m);
      if (forSelected(m)) renderBelief(m.belief);
    },
    auth_ok: tokenAccepted,
    auth_refused: tokenRefused,
    active_path: (m) => forSelected(m) && emit("active_path", { path: m.active_path }),
    open: () => {
      setConsoleReachable(true);
      setBeliefReachable(true);
      setControlReachable(true);
      fleetNews("open", {});
      if (opened) {
        loadCommands();
        loadVehicle();
        loadControl();
        if (!session) loadSession().then((again) => again && loadTraining(again.mode));
      }
      opened = true;
    },
    // what the page last heard of the vehicle link and the belief is no longer current
    close: () => {
      setConsoleReachable(false);
      setBeliefReachable(false);
      setControlReachable(false);
      fleetNews("close", {});
    },
  });
  startVehicleFallback();

  const s = await loadSession();
  loadTraining(s ? s.mode : null);
  const fleetReady = loadFleet(); // with a fleet: the selector, the rows, Surface all
  loadVehicle();
  const dictionaryReady = loadDictionary();
  // the command list does not need the dictionary (only its units): do not wait long for it
  await Promise.race([dictionaryReady, new Promise((resolve) => setTimeout(resolve, 2000))]);
  loadCommands();
  await dictionaryReady;
  await fleetReady; // a fleet: every preview names its vehicle from the first
  loadVehicle(); // again, now that the units are known
  initAuthoring({ onSent: upsertCommand });
  $("script-add").addEventListener("click", () => addStep(current()));
  initScript();
  initLog();
  initReplay();
  loadLog();
  renderSession(session);
}

// a 401/403 on any call: ask the server again what this token is worth, and show it
window.addEventListener("nemesys:auth-error", debounce(() => loadSession(), 500));

window.addEventListener("unhandledrejection", (event) => {
  event.preventDefault();
  notifyError("unexpected error", event.reason);
});

main().catch((err) => notifyError("start-up", err));
