"""``NEMESYS_VEHICLES`` (issue 23): read by :func:`vehicle_contract.fleet.parse_vehicles`, a
fault stops ``nemesys console`` before anything starts (exit 2, one line naming the setting and
what is allowed); unset, the console's one vehicle as always."""

from __future__ import annotations

import io

import pytest
from pydantic import ValidationError

from backend.settings import Settings
from cli.common import EXIT_USAGE
from cli.main import main
from tests.backend.conftest import clear_nemesys_env


def test_no_fleet_is_the_single_vehicle() -> None:
    assert Settings(target="tcp://127.0.0.1:9").fleet == ()


def test_a_count_or_a_list_names_the_fleet() -> None:
    three = Settings(target="tcp://127.0.0.1:9", vehicles=" 3 ").fleet
    assert [(v.name, v.address) for v in three] == [("auv1", 1), ("auv2", 2), ("auv3", 3)]
    listed = '[{"name": "alpha", "address": 4}, {"name": "beta", "address": 9}]'
    two = Settings(target="tcp://127.0.0.1:9", vehicles=listed).fleet
    assert [(v.name, v.address) for v in two] == [("alpha", 4), ("beta", 9)]


@pytest.mark.parametrize(
    ("value", "said"),
    [
        ("0", "1 to 15 vehicles"),
        ("16", "1 to 15 vehicles"),
        ('[{"name": "a", "address": 0}]', "0 is every vehicle"),
        ('[{"name": "all", "address": 1}]', "not 'all'"),
        ('[{"name": "a", "address": 1}, {"name": "b", "address": 1}]', "given twice"),
        ("three", "neither a count nor JSON"),
    ],
)
def test_a_fleet_fault_is_refused_naming_it(value: str, said: str) -> None:
    with pytest.raises(ValidationError) as err:
        Settings(target="tcp://127.0.0.1:9", vehicles=value)
    assert said in str(err.value)


def test_a_fleet_takes_no_single_namespace_and_may_be_relayed() -> None:
    with pytest.raises(ValidationError, match="leave vehicle_namespace empty"):
        Settings(target="tcp://127.0.0.1:9", vehicles="2", vehicle_namespace="auv1")
    url = "postgresql://u@127.0.0.1/nemesys"
    # a shore (no transmitter) with the ship's fleet: tests/backend/relay/test_relay_fleet.py
    assert len(Settings(vehicles="2", target="relay", database_url=url).fleet) == 2
    with pytest.raises(ValidationError, match="NEMESYS_DATABASE_URL"):
        Settings(vehicles="2", target="relay")  # a relay needs the shared log, fleet or not
    assert len(Settings(vehicles="2").fleet) == 2  # training: the fleet simulator


def test_the_console_stops_before_starting_naming_the_setting(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    clear_nemesys_env(monkeypatch)
    monkeypatch.setenv("NEMESYS_VEHICLES", "20")
    monkeypatch.setenv("NEMESYS_TARGET", "tcp://127.0.0.1:9")
    status = main(["console"], out=io.StringIO())
    err = capsys.readouterr().err
    assert status == EXIT_USAGE
    assert err.startswith("nemesys console: setting vehicles:") and "1 to 15" in err
    assert len(err.strip().splitlines()) == 1
