"""Reading scenario files (JSON or TOML) with exactly the documented keys."""

from __future__ import annotations

import json
import stat
import sys
import tomllib
from dataclasses import replace
from pathlib import Path
from typing import Any

from spec.errors import BadInput, OptionError, ScenarioError
from spec.scenario import Scenario, make_scenario, measured_speeds, sensed
from spec.sound import sound_from_table, sound_to_table

REQUIRED_KEYS = ("lane", "left_lane", "right_lane")
OPTIONAL_KEYS = ("targets", "model", "horizon", "cell_m", "bounds", "left_m", "right_m", "left_mps", "right_mps")
#: The keys given per vehicle of a lane, in the file's order of its cells (the scenario sorts them).
PER_VEHICLE_KEYS = ("left_m", "right_m", "left_mps", "right_mps")
SUFFIXES = (".json", ".toml")
MAX_BYTES = 256 * 1024  # a scenario is a few hundred bytes: anything near this is not one


def load_scenario(path: str | Path, cell_m: object = None) -> Scenario:
    """The scenario in ``path``; every problem raises ScenarioError naming the file. ``cell_m`` (the ``--cell-m``
    option) is the grid of a file that names none; a file that names another grid is bad input."""
    source = str(path)
    try:
        data = _read(Path(path))
        if cell_m is not None and "cell_m" in data:
            if data["cell_m"] != cell_m:
                raise OptionError("--cell-m", cell_m, f"{source} names cell_m = {data['cell_m']!r}, its own grid")
        elif cell_m is not None:
            data = {**data, "cell_m": cell_m}
        return scenario_from_dict(data)
    except ScenarioError as err:
        raise err.with_source(source) from None


def _read(path: Path) -> dict[str, Any]:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise ScenarioError("file", path.name, "unknown format: use a .json or .toml file")
    try:
        info = path.stat()  # before opening: opening a FIFO would wait for a writer
        if not stat.S_ISREG(info.st_mode):
            raise ScenarioError("file", path.name, "not a regular file (a device, a pipe or a directory)")
        if info.st_size > MAX_BYTES:
            raise ScenarioError("file", path.name, f"{info.st_size} bytes: larger than {MAX_BYTES} (not a scenario)")
        with path.open("rb") as handle:
            raw = handle.read(MAX_BYTES + 1)
    except OSError as err:
        raise ScenarioError("file", path.name, f"cannot read: {err.strerror or err}") from None
    if len(raw) > MAX_BYTES:
        raise ScenarioError("file", path.name, f"larger than {MAX_BYTES} bytes (not a scenario)")
    try:
        text = raw.decode("utf-8-sig")  # a byte-order mark, as some editors write, is not part of the text
        data = json.loads(text, object_pairs_hook=_unique) if suffix == ".json" else tomllib.loads(text)
    except UnicodeDecodeError:
        raise ScenarioError("file", path.name, "not UTF-8 text") from None
    except DuplicateKey as err:
        raise ScenarioError("file", path.name, f"the key {err.key!r} is given twice") from None
    except json.JSONDecodeError as err:
        raise ScenarioError("file", path.name, f"malformed JSON: {err.msg} (line {err.lineno})") from None
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError("file", path.name, f"malformed TOML: {err}") from None
    except RecursionError:
        raise ScenarioError("file", path.name, "nested too deeply (not a scenario)") from None
    except ValueError as err:  # what the parsers leave to int(): a number of thousands of digits
        digits = f"a number of more than {sys.get_int_max_str_digits()} digits"
        raise ScenarioError("file", path.name, digits if "digits" in str(err) else f"unreadable: {err}") from None
    if not isinstance(data, dict):
        raise ScenarioError("file", path.name, "the top level must be an object")
    return data


class DuplicateKey(ValueError):
    def __init__(self, key: str) -> None:
        super().__init__(key)
        self.key = key


def _unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    """A JSON object whose keys are all different (as TOML requires): JSON alone would keep the last value."""
    data: dict[str, Any] = {}
    for key, value in pairs:
        if key in data:
            raise DuplicateKey(key)
        data[key] = value
    return data


def scenario_from_dict(data: dict[str, Any]) -> Scenario:
    """A validated scenario from a parsed file's top-level table."""
    for key in data:
        if key not in REQUIRED_KEYS + OPTIONAL_KEYS:
            raise ScenarioError(key, data[key], f"unknown key (allowed: {', '.join(REQUIRED_KEYS + OPTIONAL_KEYS)})")
    for key in REQUIRED_KEYS:
        if key not in data:
            raise ScenarioError(key, None, "missing required key")
    fields = {k: v for k, v in data.items() if k not in ("bounds", *PER_VEHICLE_KEYS)}
    scenario = make_scenario(**fields)
    for keys, attach in ((("left_m", "right_m"), sensed), (("left_mps", "right_mps"), measured_speeds)):
        if not any(k in data for k in keys):
            continue
        # given in the file's order of its cells; the scenario sorts them
        left, right = _cell_order(data["left_lane"], data.get(keys[0])), _cell_order(data["right_lane"],
                                                                                    data.get(keys[1]))
        try:
            scenario = attach(scenario, [data[keys[0]][i] for i in left] if left else data.get(keys[0]),
                              [data[keys[1]][i] for i in right] if right else data.get(keys[1]))
        except ScenarioError as err:  # name the interval as the file numbers it
            key, _, rest = err.key.partition("[")
            order = left if key == keys[0] else right
            if rest and order:
                raise ScenarioError(f"{key}[{order[int(rest.rstrip(']'))]}]", err.value, err.reason) from None
            raise
    if "bounds" not in data:
        return scenario
    try:
        sound = sound_from_table(data["bounds"])
    except BadInput as err:
        raise ScenarioError(err.key, err.value, err.reason) from None
    return replace(scenario, sound=sound)


def _cell_order(cells: object, intervals: object) -> list[int] | None:
    """The file's indices of a lane's sensed intervals in the scenario's (ascending) order of its cells; None when
    there is nothing to reorder (``sensed`` names what is wrong with it)."""
    if isinstance(cells, list) and isinstance(intervals, list) and len(cells) == len(intervals):
        return sorted(range(len(cells)), key=lambda i: cells[i])
    return None


def scenario_to_dict(scenario: Scenario) -> dict[str, Any]:
    """The file representation of a scenario (inverse of ``scenario_from_dict``)."""
    return {
        "lane": scenario.lane.value,
        "left_lane": list(scenario.left_lane),
        "right_lane": list(scenario.right_lane),
        "targets": scenario.targets,
        "model": scenario.model.value,
        "horizon": scenario.horizon,
        "cell_m": scenario.grid.to_json(),
        **({"bounds": sound_to_table(scenario.sound)} if scenario.sound is not None else {}),
        **({"left_m": [list(e) for e in scenario.left_m]} if scenario.left_m is not None else {}),
        **({"right_m": [list(e) for e in scenario.right_m]} if scenario.right_m is not None else {}),
        **({"left_mps": [list(e) for e in scenario.left_mps]} if scenario.left_mps is not None else {}),
        **({"right_mps": [list(e) for e in scenario.right_mps]} if scenario.right_mps is not None else {}),
    }
