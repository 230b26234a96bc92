"""Scenario files: JSON and TOML mean the same, and what the suite writes it reads back unchanged."""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from hypothesis import given

from oracle.shrink import to_toml
from spec.errors import ScenarioError
from spec.files import load_scenario, scenario_to_dict
from spec.scenario import Scenario
from tests.conftest import scenarios


@given(scenarios())
def test_json_and_toml_round_trip_to_the_same_scenario(scenario: Scenario) -> None:
    with tempfile.TemporaryDirectory() as folder:
        as_json, as_toml = Path(folder) / "s.json", Path(folder) / "s.toml"
        as_json.write_text(json.dumps(scenario_to_dict(scenario)))
        as_toml.write_text(to_toml(scenario))
        assert load_scenario(as_json) == load_scenario(as_toml) == scenario


def test_cells_are_sorted_and_optional_keys_default(tmp_path: Path) -> None:
    path = tmp_path / "s.json"
    path.write_text('{"lane": "left", "left_lane": [30, 12], "right_lane": [40, 20]}')
    scenario = load_scenario(path)
    assert (scenario.left_lane, scenario.right_lane, scenario.targets, scenario.horizon) == ((12, 30), (20, 40), 0, 30)


def test_error_names_file_key_value_and_reason(tmp_path: Path) -> None:
    path = tmp_path / "s.toml"
    path.write_text('lane = "left"\nleft_lane = [12, 60]\nright_lane = []\n')
    with pytest.raises(ScenarioError) as err:
        load_scenario(path)
    assert str(err.value) == f"{path}: left_lane[1]=60: cell outside the sensed window 0..50"


def test_boolean_is_not_a_cell(tmp_path: Path) -> None:
    path = tmp_path / "s.json"
    path.write_text('{"lane": "left", "left_lane": [true], "right_lane": []}')
    with pytest.raises(ScenarioError, match="integer"):
        load_scenario(path)


def test_measured_intervals_round_trip_in_the_files_cell_order_and_bad_ones_name_their_key(tmp_path: Path) -> None:
    """What a snapshot measured (``left_m``, ``right_m``) is read in the order of the file's cells and written
    back as the scenario holds it (sorted); an interval that is not two finite numbers, is upside down or lies
    outside its cell's extent is bad input naming its key."""
    path = tmp_path / "s.json"
    path.write_text('{"lane": "left", "left_lane": [14, 11], "right_lane": [], "left_m": [[80, 85.5], [19.5, 19.5]]}')
    scenario = load_scenario(path)
    assert scenario.left_lane == (11, 14) and scenario.left_m == ((19.5, 19.5), (80.0, 85.5))
    assert scenario.right_m is None
    again = tmp_path / "again.json"
    again.write_text(json.dumps(scenario_to_dict(scenario)))
    assert load_scenario(again) == scenario
    for bad, reason, key in (('[[19.5, 19.5]]', "must be a list of 2", "left_m="),
                             ('[[80, "x"], [20, 21]]', "two finite numbers", "left_m[0]="),
                             ('[[85, 80], [20, 21]]', "lower end is above", "left_m[0]="),
                             ('[[80, 81], [200, 201]]', "outside its cell 11", "left_m[1]=")):
        path.write_text(f'{{"lane": "left", "left_lane": [14, 11], "right_lane": [], "left_m": {bad}}}')
        with pytest.raises(ScenarioError, match=reason) as err:
            load_scenario(path)
        assert f"{path}: {key}" in str(err.value)  # numbered as the file numbers its intervals


def test_measured_speeds_round_trip_in_the_files_cell_order_and_bad_ones_name_their_key(tmp_path: Path) -> None:
    """Each vehicle's measured speed interval (``left_mps``, ``right_mps``) is read in the order of the file's cells
    and written back as the scenario holds it; a list of the wrong length, a speed that is not two finite numbers,
    upside down or below 0 is bad input naming its key, and so is an acceleration bound of 0 or below."""
    path = tmp_path / "s.json"
    path.write_text('{"lane": "left", "left_lane": [14, 11], "right_lane": [30], "left_mps": [[5, 6], [0, 0]], '
                    '"right_mps": [[8, 9.5]], "bounds": {"accel_mps2": 2.5, "brake_mps2": 8}}')
    scenario = load_scenario(path)
    assert scenario.left_lane == (11, 14) and scenario.left_mps == ((0.0, 0.0), (5.0, 6.0))
    assert scenario.right_mps == ((8.0, 9.5),)
    assert scenario.sound is not None
    assert (scenario.sound.speed_change.accel_mps2, scenario.sound.speed_change.brake_mps2) == (2.5, 8.0)
    again = tmp_path / "again.json"
    again.write_text(json.dumps(scenario_to_dict(scenario)))
    assert load_scenario(again) == scenario
    for key, bad, reason, named in (("left_mps", '[[5, 6]]', "must be a list of 2", "left_mps="),
                                    ("left_mps", '[[5, "x"], [0, 0]]', "two finite numbers", "left_mps[0]="),
                                    ("left_mps", '[[5, NaN], [0, 0]]', "two finite numbers", "left_mps[0]="),
                                    ("left_mps", '[[6, 5], [0, 0]]', "lower end is above", "left_mps[0]="),
                                    ("left_mps", '[[5, 6], [-1, 0]]', "no vehicle drives backwards", "left_mps[1]="),
                                    ("right_mps", '[[1, 2], [3, 4]]', "one per vehicle of right_lane", "right_mps="),
                                    ("bounds", '{"accel_mps2": 0}', "above 0", "bounds.accel_mps2="),
                                    ("bounds", '{"brake_mps2": -2}', "above 0", "bounds.brake_mps2=")):
        path.write_text(f'{{"lane": "left", "left_lane": [14, 11], "right_lane": [30], "{key}": {bad}}}')
        with pytest.raises(ScenarioError, match=reason) as err:
            load_scenario(path)
        assert f"{path}: {named}" in str(err.value)
