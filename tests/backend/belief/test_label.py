"""A fleet vehicle's label, one wording for the console's 3D view and the live Foxglove
view."""

from __future__ import annotations

from backend.belief.label import fleet_label


def test_the_label_names_the_vehicle_its_address_its_command_and_where_it_is() -> None:
    text = fleet_label(
        "auv2", 2, ("command", "circle", 0.99994), (1.25, 20.0, 2.0), "telemetry", None
    )
    assert text == "auv2 (address 2)\ncircle p 99.99 %\nx 1.2 y 20.0 m, depth 2.0 m (fix)"
    reckoned = fleet_label("auv3", 3, ("last_known", None, 1.0), (0, 40, 0), "dead_reckoning", 3.5)
    assert reckoned.endswith("(dead-reckoned +-3.5 m)")
    assert "holding p 100 %" in reckoned
    unknown = fleet_label("auv4", 4, ("unknown", None, 0.0), (0, 0, 0), "assumed", None)
    assert unknown.startswith("auv4 (address 4)\nunknown p 0 %\n") and unknown.endswith("(assumed)")
    # a p below 1 never reads 100 %
    nearly = fleet_label("a", 1, ("command", "x", 0.999999), (0, 0, 0), "assumed", None)
    assert "p 99.9999 %" in nearly
