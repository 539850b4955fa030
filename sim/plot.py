"""PNG plots of a scenario run: plan view of the track over the planned paths, depth in time.

matplotlib (Agg backend, no display) is imported here only, so nothing else pays for it.
The plan view shows east to the right and north up (a chart), converted from NED here.
"""

from __future__ import annotations

import pathlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from sim.scenarios import ScenarioResult


def plot_scenario(result: ScenarioResult, path: str | pathlib.Path) -> pathlib.Path:
    """Write the PNG for ``result`` to ``path``; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = pathlib.Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    sc = result.scenario
    track = result.track
    t_retask = result.acks[sc.retask]["t_s"] if len(result.acks) > sc.retask else None
    if sc.name == "tank":  # the vehicle hovers in place: depth in time is the whole story
        fig, ax_depth = plt.subplots(1, 1, figsize=(9, 4.5))
        fig.suptitle(sc.title, fontsize=11)
        _depth_panel(ax_depth, result)
        return _save(fig, out, plt)
    fig, (ax_map, ax_depth) = plt.subplots(1, 2, figsize=(12, 5), width_ratios=(1, 1.3))
    fig.suptitle(sc.title, fontsize=11)
    colours = ("#9aa5b1", "#1f77b4", "#2ca02c", "#d62728", "#9467bd")
    for k, plan in enumerate(result.plans):
        if plan is None:
            continue
        label = f"plan {k + 1}: {plan.pattern}"
        ax_map.plot(
            plan.path.ys, plan.path.xs, "--", lw=1, color=colours[k % len(colours)], label=label
        )
    before = [s for s in track if t_retask is None or s.t_s <= t_retask]
    after = [s for s in track if t_retask is not None and s.t_s > t_retask]
    ax_map.plot([s.y_m for s in before], [s.x_m for s in before], color="k", lw=1.5, label="track")
    if after:
        ax_map.plot(
            [s.y_m for s in after],
            [s.x_m for s in after],
            color="#ff7f0e",
            lw=1.5,
            label="track after retask",
        )
    ax_map.set_xlabel("east (m)")
    ax_map.set_ylabel("north (m)")
    ax_map.set_aspect("equal", adjustable="datalim")
    ax_map.grid(alpha=0.3)
    ax_map.legend(fontsize=8, loc="best")
    _depth_panel(ax_depth, result)
    return _save(fig, out, plt)


def _depth_panel(ax: Any, result: ScenarioResult) -> None:
    track = result.track
    ts = [s.t_s for s in track]
    ax.plot(ts, [s.depth_ref_m for s in track], color="#1f77b4", lw=1, label="depth reference")
    ax.plot(ts, [s.z_m for s in track], color="k", lw=1.2, label="depth")
    for ack in result.acks:
        ax.axvline(ack["t_s"], color="#d62728", lw=0.8, alpha=0.6)
    ax.invert_yaxis()
    ax.set_xlabel("time (s)")
    ax.set_ylabel("depth (m)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="best")


def _save(fig: Any, out: pathlib.Path, plt: Any) -> pathlib.Path:
    fig.tight_layout()
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
