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
