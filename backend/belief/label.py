"""A fleet vehicle's label, as the console's 3D view and the live Foxglove view both draw it:
the vehicle, what it is believed to run and where it is believed to be (one wording, one
place: neither view loads the other's library)."""

from __future__ import annotations

from typing import Final

from backend.belief.commands import percent_text

__all__ = ["fleet_label"]

#: How each position source is said on a label.
_BASIS: Final = {"telemetry": "fix", "dead_reckoning": "dead-reckoned", "assumed": "assumed"}


def fleet_label(
    name: str,
    address: int | None,
    command: tuple[str, str | None, float],
    position: tuple[float, float, float],
    source: str,
    sigma_m: float | None,
) -> str:
    """Three short lines (vehicles a few tens of metres apart keep their labels apart)::

        auv2 (address 2)
        circle p 99.99 %
        x 0.0 y 20.0 m, depth 2.0 m (fix)

    the vehicle, what it is believed to run (``command``: the belief's kind, pattern and p)
    and where it is believed to be (NED m: north, east, depth; the position's source and
    uncertainty)."""
    kind, pattern, p = command
    what = "unknown" if kind == "unknown" else pattern or "holding"
    basis = _BASIS.get(source, source)
    if source != "telemetry" and sigma_m is not None:
        basis += f" +-{sigma_m:.1f} m"
    x, y, z = position
    where = f"x {x:.1f} y {y:.1f} m, depth {z:.1f} m"
    named = name if address is None else f"{name} (address {address})"
    return f"{named}\n{what} p {percent_text(p)}\n{where} ({basis})"
