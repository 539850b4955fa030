"""The results page's two paper-wide sections: every figure and table of the paper with its
status here, and where we differ (including the paper's own inconsistencies).

:data:`PAPER_ITEMS` is the complete list of the paper's ``\\label{fig:...}`` and
``\\label{tab:...}`` (14 labels), plus the named parts of its evaluation that have no label
(the controllability rank, the Gazebo world, Cfg #1/#2's rates). :func:`paper_labels` reads the
labels out of the paper's LaTeX source; ``nemesys results`` checks the list against it when
the paper is at hand (:data:`PAPER_TEX`), and the tests check the page against the list.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from analysis.twin import TwinReport
from bench.reconfig import PAPER_DECODE_MS, PAPER_RSS_MB, ReconfigReport
from codec import DEFAULT_BITRATE_BPS, FRAME_BITS, airtime_s

Section = tuple[str, list[str]]
#: Where the paper's source sits next to a checkout (not part of the repository).
PAPER_TEX = Path(__file__).resolve().parents[2] / "shared" / "paper" / "nemesys-paper.tex"
STATUSES = ("reproduced", "estimated", "not reproduced")

#: The paper's figures quoted in the differences.
PAPER_BUDGET_MS = 1.0  # "an upper limit of 1 ms per command transmission"
PAPER_M = 7
PAPER_N, PAPER_K, PAPER_T = 72, 56, 2  # "(n=72, k=56, T=2)", "n-k = 16 redundancy bits"
PAPER_SQUARE_MS, PAPER_SQUARE_WP = 26.0, 4
PAPER_CIRCLE_MS, PAPER_CIRCLE_WP = 1620.0, 36
TANK_STEP_M = 0.5
PAPER_HEAVE_MPS = 0.0731


@dataclass(frozen=True, slots=True)
class PaperItem:
    label: str  # the paper's \label, or a short name for an unlabelled part
    what: str
    status: str  # one of STATUSES
    where: str  # the section here, or why not


#: Section titles on the page (the item's ``where`` names them).
PAPER_ITEMS: tuple[PaperItem, ...] = (
    PaperItem("fig:fig1", "the vehicle deployed in the wild (photographs)", "not reproduced",
              "photographs of the physical vehicle; there is no hardware here"),
    PaperItem("fig:system_design", "the robot, its CAD, exploded view, dimensions and ME antenna",
              "not reproduced",
              "mechanical drawings of the hardware; the twin takes only the mass (13.9 kg) and "
              "GM from the paper, its other parameters are estimates (`docs/simulator.md`)"),
    PaperItem("tab:battery_power_consumption_table", "battery % after 1-5 h", "reproduced",
              "section *Battery*; the battery model is a fit to these five points "
              "(calibrated, not predicted)"),
    PaperItem("fig:ros_graph", "the ROS 2 node and topic graph", "not reproduced",
              "the vehicle's ROS 2 software is not part of this repository; the console talks "
              "to the twin through a rosbridge websocket, whose topics are in `docs/bridge.md`"),
    PaperItem("fig:design_comparison", "drawings of the three configurations (CG, CB, thrusters)",
              "not reproduced",
              "drawings; Cfg #3's thruster layout is the twin's (section *Controllability*), and "
              "the three GMs are run in section *Passive stability*"),
    PaperItem("fig:stability_comparison", "passive stability under a disturbance: Cfg #2 "
              "flips, Cfg #3 keeps its posture", "reproduced",
              "section *Passive stability*: the twin pushed in roll with GM 0, -2.0 and 6.5 mm; "
              "Cfg #1/#2 are the Cfg #3 model with only GM changed, so the outcomes are the "
              "paper's and the time scales the twin's"),
    PaperItem("tab:design_comparison", "GM, heave and yaw rates of Cfg #1-#3", "reproduced",
              "Cfg #3 only, section *Stability and manoeuvrability* (heave and yaw calibrated "
              "to the paper's figures; GM is an input); Cfg #1/#2 rates: see below"),
    PaperItem("Cfg #1/#2 heave and yaw rates", "3.5 / 26.3 mm/s, 5.7 / 9.9 deg/s",
              "not reproduced",
              "earlier hardware the twin does not model: the paper gives no masses, drag or "
              "thrust for them, and Cfg #1's loss is the antenna blocking its heave thruster's "
              "flow, which the model has no term for"),
    PaperItem("controllability rank", "rank 4 of the thruster configuration matrix B",
              "reproduced", "section *Controllability*: B from the twin's layout, rank 4, "
              "sway and pitch not actuated"),
    PaperItem("fig:coding_scheme", "the encoding and decoding scheme", "reproduced",
              "the codec (`codec/`) and `docs/protocol.md`: the 100-bit frame's layout, a "
              "worked example and the decoder"),
    PaperItem("tab:command_dict", "the command dictionary (IDs 0-7, fields j1-j6)", "reproduced",
              "`codec/_dictionary.py` and `docs/protocol.md` section 3: the same 8 patterns, IDs "
              "and fields (plus ID 15, surface, ours)"),
    PaperItem("fig:encoding_eval", "decoding success against BER for T = 1..4; efficiency",
              "reproduced", "section *Encoding evaluation* (Monte Carlo through the real "
              "decoder)"),
    PaperItem("fig:sim_reconfig", "three retasking scenarios in the digital twin", "estimated",
              "section *Retasking scenarios*: the three retasks flown on our twin; the paper "
              "gives no geometry, depths or times, so ours are estimates"),
    PaperItem("Gazebo world and sensors", "the paper's Gazebo twin: a 60 m deep world with "
              "shipwreck and BOP panel, camera, IMU and pressure plugins", "not reproduced",
              "our twin is a pure-Python 4-DOF model with a depth sensor and no world, "
              "structures or cameras (`docs/simulator.md`); the latencies of Table "
              "`tab:reconfig_metrics` are measured on the onboard path and do not need them"),
    PaperItem("tab:reconfig_metrics", "decode and replan latency, memory", "reproduced",
              "section *Mission adaptation latency and memory*: the paper's protocol on our "
              "onboard path, on different hardware"),
    PaperItem("fig:depth_control", "tank test: depth steps over 75 s", "reproduced",
              "section *Depth control in the tank*: the twin in the tank scenario; the command "
              "times are estimates (the paper gives them only in its figure)"),
    PaperItem("fig:field_eval", "open-water rectangle: ORB-SLAM3 sparse map and trajectory",
              "not reproduced",
              "field trials in freshwater springs; the trajectory is ORB-SLAM3 on the forward "
              "monocular camera's images, which are not available, and the twin has no camera "
              "or visual odometry; the rectangle itself is the `square` pattern the twin flies"),
)  # fmt: skip


def paper_labels(tex: str) -> list[str]:
    """Every ``\\label{fig:...}`` and ``\\label{tab:...}`` in the paper's LaTeX, in order."""
    return re.findall(r"\\label\{((?:fig|tab):[^}]+)\}", tex)


def check_against_paper(tex_path: Path = PAPER_TEX) -> int | None:
    """When the paper's source is at ``tex_path``: raise unless :data:`PAPER_ITEMS` names
    exactly its labels, and return how many; ``None`` when the paper is not there."""
    if not tex_path.is_file():
        return None
    labels = paper_labels(tex_path.read_text(encoding="utf-8"))
    ours = {i.label for i in PAPER_ITEMS if i.label.startswith(("fig:", "tab:"))}
    if set(labels) != ours:
        raise ValueError(f"the paper's labels changed: {sorted(set(labels) ^ ours)}")
    return len(labels)


def items_section() -> Section:
    rows = [
        [f"`{i.label}`" if ":" in i.label else i.label, i.what, f"**{i.status}**", i.where]
        for i in PAPER_ITEMS
    ]
    counts = {s: sum(1 for i in PAPER_ITEMS if i.status == s) for s in STATUSES}
    return "Every figure and table of the paper", [
        "Each of the paper's 14 figures and tables (by its LaTeX label), and the unlabelled "
        "parts of its evaluation, with what this page does with it. *Reproduced*: measured "
        "here the paper's way and compared (on the twin where the paper used hardware, as "
        "stated); *estimated*: redone, but on inputs the paper does not give, so only the "
        "shape compares; *not reproduced*: with the reason.",
        "",
        "| paper item | what | status | where, or why not |",
        "| --- | --- | --- | --- |",
        *("| " + " | ".join(c.replace("|", "\\|") for c in r) + " |" for r in rows),
        "",
        ", ".join(f"{n} {s}" for s, n in counts.items()) + ".",
    ]


def differences(rep: ReconfigReport, twin: TwinReport) -> Section:
    airtime_ms = airtime_s(DEFAULT_BITRATE_BPS) * 1e3
    bits_in_budget = DEFAULT_BITRATE_BPS * PAPER_BUDGET_MS / 1e3
    rate_for_budget = FRAME_BITS / (PAPER_BUDGET_MS / 1e3)
    parity7 = PAPER_M * PAPER_T
    paper_eff = PAPER_K / (PAPER_K + 2 * PAPER_M * PAPER_T)
    min_descent = TANK_STEP_M / PAPER_HEAVE_MPS
    sq_norm = PAPER_SQUARE_MS / PAPER_SQUARE_WP
    ci_norm = PAPER_CIRCLE_MS / PAPER_CIRCLE_WP
    return "Where we differ, and the paper's own inconsistencies", [
        f"* **m = {PAPER_M} against n - k = {PAPER_N - PAPER_K}.** The paper's code is "
        f"(n = {PAPER_N}, k = {PAPER_K}, T = {PAPER_T}) with n - k = 16 redundancy bits, "
        f"and its efficiency formula uses m = {PAPER_M}. A binary BCH code correcting T = 2 "
        f"over GF(2^{PAPER_M}) has at most m T = {parity7} parity bits, giving "
        f"({PAPER_K + parity7}, {PAPER_K}), not ({PAPER_N}, {PAPER_K}); 16 parity bits for "
        "T = 2 means GF(2^8) (m = 8), the true shortened (72, 56) BCH code, which is what we "
        "implement (`docs/protocol.md` section 5). The likely origin is `bchlib.BCH(2, m=7)`, "
        "whose 14 parity bits are padded to 2 bytes (2 unprotected bits). The formula "
        f"k / (k + 2mT) = {PAPER_K}/{PAPER_K + 2 * PAPER_M * PAPER_T} = {paper_eff:.3f} is "
        f"then not the code rate either ({PAPER_K}/{PAPER_N} = {PAPER_K / PAPER_N:.3f}): a "
        "binary BCH code needs m T parity bits, not 2 m T.",
        f"* **A 1 ms transmission budget that 100 bits at 36 kb/s cannot meet.** The paper "
        f'imposes "an upper limit of {PAPER_BUDGET_MS:g} ms per command transmission" on a '
        f"{DEFAULT_BITRATE_BPS / 1e3:g} kb/s link, but a {FRAME_BITS}-bit frame takes "
        f"{FRAME_BITS} / {DEFAULT_BITRATE_BPS:,} s = **{airtime_ms:.2f} ms** on air; 1 ms "
        f"carries {bits_in_budget:g} bits, and a 1 ms frame would need "
        f"{rate_for_budget / 1e3:g} kb/s. Our emulated channel uses the real airtime.",
        '* **"Approximately 5 s" transients against the 73.1 mm/s heave limit.** At the '
        f"paper's own full-thrust heave rate a {TANK_STEP_M:g} m descent needs at least "
        f"{TANK_STEP_M:g} / 0.0731 = {min_descent:.2f} s ({twin.descent_min_s:.2f} s from rest "
        "in the twin, which must accelerate); only ascents, helped by the positive buoyancy, "
        "fit 5 s (section *Depth control in the tank*).",
        "* **Normalised replan latency makes long paths look cheap.** Dividing the replan "
        "time by the number of waypoints hides the total a vehicle waits for: the paper's "
        f"own examples are {PAPER_SQUARE_MS:g} ms for a {PAPER_SQUARE_WP}-waypoint square "
        f"({sq_norm:.1f} ms/wp) and {PAPER_CIRCLE_MS / 1e3:g} s for a "
        f'{PAPER_CIRCLE_WP}-waypoint circle ({ci_norm:.0f} ms/wp), so "less than 50 ms '
        "total latency\" holds per waypoint but not for the circle's 1.62 s total. The "
        "figure also depends on how finely a planner discretises the same path. We print "
        "the totals beside the normalised figures.",
        "* **Decode latency on different hardware and software.** The paper's "
        f"{PAPER_DECODE_MS:g} ms was measured on an Intel Core i7 under ROS 2; ours on "
        f"{rep.machine}, in-process, a few microseconds either way between reruns (the "
        "spread is printed beside the table).",
        f'* **Memory.** "Peak RSS during decoding and replanning" ({PAPER_RSS_MB:g} MB) '
        "includes the interpreter; we give both the whole process's peak and the part the "
        "decode and replan add, in MiB (the kernel's kB are KiB).",
        "* **Calibrated, not predicted.** The twin's heave and yaw rates and its battery "
        "curve were fitted to the paper's figures; that they match is a check of the fit. "
        "Only Cfg #3 is modelled; Cfg #1 and #2 differ from it in GM alone in the "
        "passive-stability runs, and their rates are not reproducible.",
        "* **Unstated geometry.** The paper gives no scenario geometry, tank command times, "
        "cruise speed, controller gains or thruster positions; ours are estimates "
        "(`docs/simulator.md`), so the tracks and step responses are the twin's, not a replay "
        "of the paper's runs.",
        "* **Battery pack.** The paper's pack is 14.8 V x 10 Ah = 148 Wh; the twin's load "
        "estimate (about 20.5 W nominal) with the fitted 9.23 %/h slope implies about 220 Wh. "
        "The curve's fast initial term (32 % with a 1.03 h time constant) looks like a "
        "voltage-based state-of-charge estimate rather than energy, so the paper's table "
        "cannot pin down the pack's energy or the vehicle's power draw.",
    ]


__all__ = [
    "PAPER_ITEMS",
    "PAPER_TEX",
    "STATUSES",
    "PaperItem",
    "check_against_paper",
    "differences",
    "items_section",
    "paper_labels",
]
