"""The live view's time: the dive's clock in nanoseconds (backend/foxglove_live/clock.py)."""

from __future__ import annotations

from backend.foxglove_live.clock import DiveClock


class Station:
    """A station clock the test moves (s)."""

    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def test_a_pose_is_stamped_at_its_own_time_from_the_dives_first_track_point() -> None:
    station, start = Station(), dict[str, float | None](t_s=None)
    clock = DiveClock(lambda: start["t_s"], station)
    assert clock.follow(1)
    start["t_s"] = 100.0  # the dive's first track point
    assert clock.heard(100.5) == 500_000_000
    assert clock.heard(103.25) == 3_250_000_000
    assert clock.at(110.0) == 10_000_000_000  # an estimate's time: no anchor


def test_without_a_track_point_the_first_pose_heard_is_the_zero() -> None:
    clock = DiveClock(lambda: None, Station())
    clock.follow(4)
    assert clock.heard(57.0) == 0
    assert clock.heard(58.0) == 1_000_000_000


def test_news_without_a_vehicle_time_runs_on_at_the_vehicle_clocks_rate() -> None:
    station = Station()
    clock = DiveClock(lambda: 0.0, station)
    clock.follow(1)
    clock.heard(10.0)
    station.t += 2.0
    clock.heard(110.0)  # 100 vehicle s in 2 station s: time scale 50
    station.t += 0.1
    assert clock.now() == 115_000_000_000  # the last pose + 0.1 s at 50x
    station.t += 1.0
    clock.heard(165.0)  # 55 s in 1.1 s: still 50x
    station.t += 1.0
    clock.heard(175.0)  # 10 s in 1 s: the operator set the time scale to 10
    station.t += 0.5
    assert clock.now() == 180_000_000_000


def test_before_any_pose_station_seconds_since_the_dive_began() -> None:
    station = Station()
    clock = DiveClock(lambda: None, station)
    station.t += 3.0
    assert clock.now() == 3_000_000_000  # no dive yet: since the view started
    assert clock.follow(2)
    assert not clock.follow(2)
    station.t += 1.5
    assert clock.now() == 1_500_000_000


def test_a_new_dive_starts_the_clock_at_zero_again() -> None:
    station, start = Station(), dict[str, float | None](t_s=0.0)
    clock = DiveClock(lambda: start["t_s"], station)
    clock.follow(1)
    assert clock.heard(500.0) == 500_000_000_000
    assert clock.follow(2)
    start["t_s"] = 3.0  # the reset vehicle's clock
    assert clock.heard(3.0) == 0
    assert clock.heard(1.0) == 0  # before the dive's start: at 0, never negative
