"""The page with a fleet (issue 23, Build item 5), at 1280x800 with 5 vehicles: the console with
``NEMESYS_VEHICLES=5`` on five in-memory vehicles behind the real onboard agent, one channel
(``tests/agent_link.py``'s ``agent_fleet``, each vehicle publishing its pose and status twice a
second: training with a fleet is not wired yet), served by uvicorn in this process.

The selector lists the five; the Send button names the selected vehicle and the send (and its
preview, prediction and script step) carries it; switching vehicles previews again from that
one; the status rows show the five (name, address, believed command with p, position basis,
link, depth and battery); SURFACE ALL, as its key, sends ``{"vehicle": "all"}`` and every row
shows its own Surface until acknowledged; a row's Surface names its vehicle; every vehicle is
on the chart and in the 3D view; nothing overlaps. The page without a fleet is the other
frontend tests' (unchanged)."""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx
import pytest
import viser
from playwright.sync_api import Browser, Page, Request, expect
from playwright.sync_api import TimeoutError as PlaywrightTimeout

from backend.app import create_app
from backend.console import Console as Runtime
from backend.settings import Settings
from planner import VehicleState
from station.link import Capability
from station.link_fleet import FleetLink
from tests.agent_link import TARGET, AgentChannel, AgentLink
from tests.backend.conftest import clear_nemesys_env, wait_until
from tests.backend.live_server import serve
from tests.frontend.conftest import TOKEN, Watched
from tests.frontend.pagekit import POLL_MS, sized_page, wait_preview
from tests.frontend.test_layout import assert_in_sight, overlap, place
from vehicle_contract.fleet import parse_vehicles

FLEET = parse_vehicles("5")
NAMES = [v.name for v in FLEET]
AUTH = {"Authorization": f"Bearer {TOKEN}"}
SURFACE_KEY = "Control+Shift+S"
#: How often each vehicle publishes its pose and status (s): its link stays green.
REPORT_S = 0.5


class ReportingAgentLink(AgentLink):
    """An in-memory vehicle that publishes its pose and status every :data:`REPORT_S`, as a
    vehicle with telemetry does (it holds still where it is)."""

    _task: asyncio.Task[None] | None = None

    async def start(self) -> None:
        await super().start()
        self._task = asyncio.create_task(self._publish())

    async def _publish(self) -> None:
        while True:
            await asyncio.sleep(REPORT_S)
            self.report()

    async def stop(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
        await super().stop()


def reporting_fleet() -> FleetLink:
    """As ``tests/agent_link.py``'s ``agent_fleet``: each vehicle 2 m deep, 20 m further east
    than the one before, on one two-way channel; and each publishing its telemetry."""
    links: dict[str, AgentLink] = {
        v.name: ReportingAgentLink(
            state=VehicleState(0.0, 20.0 * i, 2.0, 0.0, 0.0, 100.0), address=v.address
        )
        for i, v in enumerate(FLEET)
    }
    return FleetLink(AgentChannel(links, Capability.ACKS_AND_TELEMETRY), links)


@dataclass
class FleetConsole:
    """The console of five in-memory vehicles (``base``: its URL), its runtime and link."""

    base: str
    runtime: Runtime
    link: FleetLink

    def get(self, path: str) -> Any:
        r = httpx.get(self.base + path, timeout=10.0, trust_env=False)
        r.raise_for_status()
        return r.json()

    def post(self, path: str, doc: Any) -> Any:
        """POST with the operator token."""
        r = httpx.post(self.base + path, json=doc, headers=AUTH, timeout=10.0, trust_env=False)
        r.raise_for_status()
        return r.json()


@pytest.fixture
def fleet_console(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[FleetConsole]:
    clear_nemesys_env(monkeypatch)
    settings = Settings(
        token=TOKEN,
        db_path=tmp_path / "log.sqlite3",
        viewer_port=0,
        target=TARGET,
        vehicles="5",
        datum_lat_deg=29.5316,
        datum_lon_deg=-82.3031,
    )
    link = reporting_fleet()
    app = create_app(settings, viewer=True, link=link)
    with serve(app) as base:
        console = FleetConsole(base, app.state.console, link)
        wait_until(lambda: all(v["pose"] for v in console.get("/api/vehicles")), what="poses")
        yield console


def open_fleet_page(w: Watched, console: FleetConsole) -> Page:
    """The page with the token (the 3D view stubbed), once the fleet's rows and the form are
    built and the first preview names its vehicle."""
    page = w.page
    w.stub_viewer()
    page.goto(f"{console.base}/?token={TOKEN}")
    expect(page.get_by_test_id("auth-state")).to_have_text(re.compile(r"^operator"))
    expect(page.locator("#fleet-rows .fleet-row")).to_have_count(len(NAMES))
    page.wait_for_function(
        "() => document.querySelector('#param-form [data-testid^=\"param-\"]') !== null",
        polling=POLL_MS,
    )
    return page


def body(request: Request) -> dict[str, Any]:
    doc: dict[str, Any] = json.loads(request.post_data or "null")
    return doc


def posted(path: str, vehicle: str | None = None) -> Any:
    """A matcher of a POST to ``path`` (for page.expect_request), naming ``vehicle`` if given."""

    def match(r: Request) -> bool:
        if r.method != "POST" or not r.url.split("?")[0].endswith(path):
            return False
        return vehicle is None or body(r).get("vehicle") == vehicle

    return match


#: The vehicles' markers (their dots) and labels not wholly inside the chart's box, as
#: ``"auv1 label"``; ``null`` until every vehicle has its marker.
FLEET_OUTSIDE_CHART = """
(count) => {
  const chart = document.getElementById('chart').getBoundingClientRect();
  const markers = [...document.querySelectorAll('#chart .chart-fleet')];
  if (markers.length !== count) return null;
  const out = [];
  for (const m of markers) {
    for (const [what, node] of [['marker', m], ['label', m.querySelector('.chart-fleet-label')]]) {
      const r = node.getBoundingClientRect();
      if (r.width === 0 || r.left < chart.left - 0.5 || r.right > chart.right + 0.5
          || r.top < chart.top - 0.5 || r.bottom > chart.bottom + 0.5) {
        out.push(`${m.dataset.vehicle} ${what}`);
      }
    }
  }
  return out;
}
"""


def fleet_outside_chart(page: Page) -> list[str] | None:
    """What of the fleet's markers and labels the chart's box does not hold (None: not every
    vehicle is on the chart yet)."""
    out: list[str] | None = page.evaluate(FLEET_OUTSIDE_CHART, len(NAMES))
    return out


def assert_fleet_inside_chart(page: Page, what: str) -> None:
    """Every vehicle's marker and label lies wholly inside the chart's box (waits for the
    chart to settle: a fit's moves end, then the labels are placed)."""
    with contextlib.suppress(PlaywrightTimeout):  # the assertion below says what is outside
        page.wait_for_function(
            f"(n) => {{ const out = ({FLEET_OUTSIDE_CHART})(n); return out && !out.length; }}",
            arg=len(NAMES),
            polling=POLL_MS,
            timeout=10_000,
        )
    assert fleet_outside_chart(page) == [], f"outside the chart's box ({what})"


def no_overlaps(page: Page, testids: list[str], what: str) -> None:
    boxes = {t: place(page, t) for t in testids}
    for i, one in enumerate(testids):
        assert boxes[one]["w"] > 0 and boxes[one]["h"] > 0, f"{one} has no size ({what})"
        for other in testids[i + 1 :]:
            assert not overlap(boxes[one], boxes[other]), (
                f"{one} overlaps {other} ({what}): {boxes}"
            )


def row_parts(name: str) -> list[str]:
    return [
        f"fleet-select-{name}",
        f"fleet-address-{name}",
        f"fleet-link-{name}",
        f"fleet-surface-{name}",
        f"fleet-belief-{name}",
        f"fleet-facts-{name}",
    ]


def fleet_labels(console: FleetConsole) -> dict[str, str]:
    viewer = console.runtime.viewer
    assert viewer is not None
    out = {}
    for node_name in viewer.node_names("/fleet/"):
        node = viewer.node(node_name)
        if isinstance(node, viser.LabelHandle):
            out[node_name.split("/")[2]] = node.text
    return out


def test_the_fleet_page_at_1280x800_with_5_vehicles(
    fleet_console: FleetConsole, browser: Browser
) -> None:
    console = fleet_console
    with sized_page(browser, 1280, 800, shot="fleet_1280x800_5_vehicles") as w:
        page = open_fleet_page(w, console)

        # the selector lists the five, the first selected and named on Send
        select = page.get_by_test_id("vehicle-select")
        options = select.locator("option").all_text_contents()
        assert options == [f"{v.name} (address {v.address})" for v in FLEET]
        expect(select).to_have_value("auv1")
        send = page.get_by_test_id("send-button")
        expect(send).to_contain_text("Send to auv1")
        expect(page.get_by_test_id("surface-button")).to_contain_text("SURFACE ALL")
        expect(page.get_by_test_id("airtime-budget")).to_have_text(
            re.compile(r"^Transmitter: (no copies queued|copies out in [\d.]+ s)")
        )

        # switching vehicles previews (and predicts) again, from that vehicle's position
        with (
            page.expect_request(posted("/api/preview", "auv3")),
            page.expect_request(posted("/api/predict", "auv3")),
        ):
            select.select_option("auv3")
        shown = page.get_by_test_id("estimates")
        expect(shown).to_have_attribute("data-command", re.compile(r'"vehicle":"auv3"'))
        expect(send).to_contain_text("Send to auv3")
        expect(page.locator("#status-title")).to_have_text("Vehicle status: auv3")
        # the frame shown is auv3's addressed one
        expect(page.get_by_test_id("frame-size")).to_have_text("(108 bits, to address 3)")
        wait_preview(page, "circle")
        expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
        # auv3 holds 40 m east of the origin: the preview starts there
        send.click()
        expect(page.get_by_test_id("confirm-from")).to_contain_text("y 40 m east")
        expect(page.locator("#confirm-title")).to_have_text("Send circle to auv3?")
        with page.expect_request(posted("/api/commands")) as sent:
            page.get_by_test_id("confirm-send").click()
        assert body(sent.value)["vehicle"] == "auv3"
        expect(page.get_by_test_id("confirm-dialog")).to_be_hidden()
        record_id = wait_until(
            lambda: next(
                (r["id"] for r in console.get("/api/commands") if r["pattern"] == "circle"), None
            ),
            what="the circle's record",
        )
        expect(page.get_by_test_id(f"command-vehicle-{record_id}")).to_have_text("to auv3")
        expect(page.get_by_test_id(f"state-{record_id}")).to_have_text("acknowledged")
        # only auv3 runs it, and only its row says so
        expect(page.get_by_test_id("fleet-belief-auv3")).to_contain_text(
            re.compile(r"circle.*p 100 %")
        )
        for name in NAMES:
            if name != "auv3":
                expect(page.get_by_test_id(f"fleet-belief-{name}")).to_contain_text("nothing")
        # a script step names the selected vehicle, and so does its preview
        page.get_by_test_id("script-add").click()
        expect(page.get_by_test_id("script-step-0-vehicle")).to_have_text("to auv3")
        with page.expect_request(posted("/api/scripts/preview")) as script:
            page.get_by_test_id("script-preview").click()
        assert [s["vehicle"] for s in body(script.value)["steps"]] == ["auv3"]

        # the status rows: the five, each with what the console says of it
        for i, v in enumerate(FLEET):
            expect(page.get_by_test_id(f"fleet-address-{v.name}")).to_have_text(
                f"address {v.address}"
            )
            facts = page.get_by_test_id(f"fleet-facts-{v.name}")
            expect(facts).to_contain_text(f"y {20 * i} m E (fix)")
            expect(facts).to_contain_text("depth 2 m")
            expect(facts).to_contain_text("battery 100 %")
            expect(page.get_by_test_id(f"fleet-link-{v.name}")).to_have_attribute(
                "data-level", "green"
            )
            expect(page.get_by_test_id(f"fleet-belief-{v.name}")).to_contain_text("p 100 %")
        expect(page.get_by_test_id("fleet-row-auv3")).to_have_class(re.compile(r"\bselected\b"))

        # every vehicle on the chart (at its believed lat/lon) and in the 3D view
        for v in FLEET:
            marker = page.get_by_test_id(f"chart-fleet-{v.name}")
            expect(marker).to_contain_text(f"{v.name} · {v.address}")
            expect(marker).to_contain_text(re.compile(r"(holding|circle) p 100 %"))
        expect(page.get_by_test_id("chart-fleet-auv3")).to_contain_text("circle")
        # the preview's fit holds every vehicle, and no label is cut by the chart's edge
        assert_fleet_inside_chart(page, "the preview's fit, auv3 selected")
        labels = wait_until(lambda: len(fleet_labels(console)) == 5 and fleet_labels(console))
        assert sorted(labels) == NAMES
        wait_until(lambda: "\ncircle p 100 %\n" in fleet_labels(console)["auv3"])

        # the layout: in sight at 1280x800 and nothing overlaps
        page.evaluate("() => window.scrollTo(0, 0)")  # the script's buttons are below the fold
        for testid in ("vehicle-select", "send-button", "estimates", "surface-button"):
            assert_in_sight(page, testid, "a fleet of 5 at 1280x800")
        for name in NAMES:
            assert_in_sight(page, f"fleet-surface-{name}", "a fleet of 5 at 1280x800")
        panels = ["author-foot", "author-scroll", "viewer-box", "chart-panel"]
        no_overlaps(page, [*panels, "fleet-panel", "status-panel"], "the columns")
        no_overlaps(page, [f"fleet-row-{n}" for n in NAMES], "the rows")
        for name in NAMES:
            no_overlaps(page, row_parts(name), f"the row of {name}")
        no_overlaps(page, ["vehicle-select", "pattern-select"], "the form")
        assert page.evaluate("() => document.documentElement.scrollWidth") <= 1280

        # SURFACE ALL, by its key: {"vehicle": "all"}, one record per vehicle, each row its own
        page.get_by_test_id("pattern-select").focus()
        with page.expect_request(posted("/api/surface")) as surface_all:
            page.keyboard.press(SURFACE_KEY)
        assert body(surface_all.value) == {"vehicle": "all"}
        for name in NAMES:
            expect(page.get_by_test_id(f"fleet-surface-state-{name}")).to_have_text(
                re.compile(r"surfacing|surface acknowledged")
            )
        for name in NAMES:
            expect(page.get_by_test_id(f"fleet-surface-state-{name}")).to_have_text(
                "surface acknowledged"
            )
        expect(page.get_by_test_id("surface-state")).to_have_text(
            "SURFACE ALL (5 vehicles): 5 acknowledged"
        )
        surfaces = [r for r in console.get("/api/commands") if r["kind"] == "surface"]
        assert sorted(r["vehicle"] for r in surfaces) == NAMES
        assert all(r["state"] == "acknowledged" for r in surfaces), surfaces

        # a row's own Surface names its vehicle, and only that one gets a record
        before = {r["id"] for r in surfaces}
        with page.expect_request(posted("/api/surface")) as one:
            page.get_by_test_id("fleet-surface-auv2").click()
        assert body(one.value) == {"vehicle": "auv2"}
        newer = wait_until(
            lambda: [
                r
                for r in console.get("/api/commands")
                if r["kind"] == "surface" and r["id"] not in before
            ],
            what="the Surface of auv2",
        )
        assert [r["vehicle"] for r in newer] == ["auv2"]
        expect(page.get_by_test_id("fleet-surface-state-auv2")).to_have_text(
            re.compile(r"surfacing|surface acknowledged")
        )
        no_overlaps(page, row_parts("auv2"), "the row of auv2 after its Surface")
        # Surface all's records are as they were: a newer Surface to one changes none of them
        expect(page.get_by_test_id("surface-state")).to_have_text(
            "SURFACE ALL (5 vehicles): 5 acknowledged"
        )
        page.evaluate("() => window.scrollTo(0, 0)")
        w.assert_clean()


def test_the_airtime_budget_and_a_repeating_surface_are_shown_as_the_console_says(
    fleet_console: FleetConsole, browser: Browser
) -> None:
    """auv5 out of earshot (its acknowledgements lost): a circle of 4 copies to it leaves a
    copy a second, the page says how long until they are out as /api/transmitter does; a
    Surface to it repeats until acknowledged, and the page says so. Back in earshot, the timed
    out circle's Retry goes to auv5, named in the dialog and the request."""
    console = fleet_console
    auv5 = console.link.vehicles["auv5"]
    assert isinstance(auv5, AgentLink)
    auv5.answer = False
    with sized_page(browser, 1280, 800) as w:
        page = open_fleet_page(w, console)
        budget = page.get_by_test_id("airtime-budget")
        expect(budget).to_have_text("Transmitter: no copies queued")
        circle = {"speed": 0.18, "depth": 3, "radius": 5, "direction": "cw"}
        doc = {"pattern": "circle", "params": circle, "vehicle": "auv5", "copies": 4}
        circle_id = console.post("/api/commands", doc)["id"]
        said = console.get("/api/transmitter")["airtime_budget_s"]
        assert 0.0 < said <= 3.1, said
        expect(budget).to_have_text(re.compile(r"^Transmitter: copies out in [0-3](\.\d)? s$"))
        shown = float(re.findall(r"in ([\d.]+) s", budget.text_content() or "")[0])
        assert shown <= said + 0.5, (shown, said)  # asked about when we asked: it counts down
        expect(budget).to_have_text("Transmitter: no copies queued", timeout=10_000)
        page.get_by_test_id("fleet-surface-auv5").click()
        expect(budget).to_contain_text("Surface repeating until acknowledged: auv5")
        expect(page.get_by_test_id("fleet-surface-state-auv5")).to_have_text(
            "surfacing... repeating until acknowledged"
        )
        auv5.answer = True  # back in earshot: the next repeat is acknowledged
        expect(page.get_by_test_id("fleet-surface-state-auv5")).to_have_text(
            "surface acknowledged", timeout=15_000
        )
        expect(budget).to_have_text("Transmitter: no copies queued")
        # the circle, never acknowledged, timed out: its Retry goes to its own vehicle
        expect(page.get_by_test_id(f"state-{circle_id}")).to_have_text("timed_out", timeout=15_000)
        page.get_by_test_id(f"retry-{circle_id}").click()
        expect(page.locator("#confirm-title")).to_have_text(
            f"Retry command {circle_id} (circle) to auv5 as a new command?"
        )
        with page.expect_request(posted(f"/api/commands/{circle_id}/retry")) as retry:
            page.get_by_test_id("confirm-send").click()
        assert body(retry.value) == {"override": False, "vehicle": "auv5"}
        retried = wait_until(
            lambda: [r for r in console.get("/api/commands") if r["retry_of"] == circle_id],
            what="the retry's record",
        )
        assert [r["vehicle"] for r in retried] == ["auv5"]
        w.assert_clean()


def plots_shown(page: Page) -> dict[str, Any]:
    """What the plots hold (``t0``, ``t``: s since the dive's start, ``depth``), their titles,
    and the vehicle they say they are of."""
    got: dict[str, Any] = page.evaluate(
        """() => {
            const box = document.getElementById('plots');
            const titles = [...box.querySelectorAll('.u-title')].map((n) => n.textContent);
            return { ...box.samplesShown(), titles, vehicle: box.dataset.vehicle ?? null };
        }"""
    )
    return got


def test_the_plots_are_the_selected_vehicles_named_in_their_titles(
    fleet_console: FleetConsole, browser: Browser
) -> None:
    """auv3 goes to 6, 7 and 8 m (a second of its clock apart) while the others hold at 2 m:
    the plots of auv1 (selected first) hold auv1's series alone; selecting auv3 loads its
    series (``GET /api/series?vehicle=auv3``), and the plots hold it, titled "Depth: auv3".
    Every series the page asked for named its vehicle."""
    console = fleet_console
    auv3 = console.link.vehicles["auv3"]
    assert isinstance(auv3, AgentLink)

    def logged() -> int:
        return len(console.get("/api/series?vehicle=auv3")["t_s"])

    for k in (1, 2, 3):  # each reported within REPORT_S and logged as a track point
        auv3.state = VehicleState(0.0, 40.0, 5.0 + k, 0.0, 0.0, 100.0 + k)
        wait_until(lambda: logged() == 1 + k, what=f"auv3's track point at {100 + k} s")  # noqa: B023
    own = {n: console.get(f"/api/series?vehicle={n}") for n in ("auv1", "auv3")}
    # (a point keeps the status heard before its pose: the depth said a second earlier)
    assert own["auv3"]["depth_m"] == [2.0, 2.0, 6.0, 7.0] and own["auv3"]["t_s"] == [0, 1, 2, 3]
    with sized_page(browser, 1280, 800) as w:
        page = open_fleet_page(w, console)
        page.wait_for_function(
            "() => document.querySelector('#plots.plots-ready') !== null"
            " && document.getElementById('plots').dataset.vehicle === 'auv1'"
            " && Number(document.getElementById('plots').dataset.logged) >= 1",
            polling=POLL_MS,
        )
        shown = plots_shown(page)
        assert shown["titles"] == ["Depth: auv1", "Battery: auv1", "Speed: auv1"]
        assert shown["depth"] == own["auv1"]["depth_m"] == [2.0]  # none of auv3's depths
        assert shown["t0"] == own["auv1"]["start_t_s"]

        with page.expect_response(
            lambda r: "/api/series?" in r.url and "vehicle=auv3" in r.url
        ) as answer:
            page.get_by_test_id("vehicle-select").select_option("auv3")
        assert answer.value.status == 200
        page.wait_for_function(
            "() => Number(document.getElementById('plots').dataset.logged) === 4",
            polling=POLL_MS,
        )
        shown = plots_shown(page)
        assert shown["titles"] == ["Depth: auv3", "Battery: auv3", "Speed: auv3"]
        assert shown["vehicle"] == "auv3"
        assert shown["t0"] == own["auv3"]["start_t_s"]
        assert (shown["t"], shown["depth"]) == ([0, 1, 2, 3], [2.0, 2.0, 6.0, 7.0])
        asked = [url for method, url in w.requests if "/api/series" in url]
        assert asked and all(re.search(r"[?&]vehicle=auv\d", url) for url in asked), asked
        w.assert_clean()
