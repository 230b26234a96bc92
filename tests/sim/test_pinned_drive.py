"""A same-seed drive is the drive recorded before the simulator was assembled from parts (commit ce09fa1).

The golden files were written by that code: ``run_drive(3, 2.0, out_dir=...)``'s summary (less its
wall-clock fields) and its trace, and written again when the executor's speed command came to divide by the
cosine of the car's heading, and again when its steering came to take off the sideways part of the car's own
speeding up (each time the same actions, plans and overtakes; the positions and deviations of the lane changes
moved by centimetres). The default assembly must reproduce both exactly: the same
kilometres, overtakes, plans, deviations and every traced number. Figures added to the summary since (safety,
traffic collisions, restarts, opportunities, containment and the sound model's counts, its committed parts and
escapes, its starts on a proved reference and from readings the last proof narrowed, the shadowed snapshots, sensed
and unseen breaches and the moves a breach ended among them, the sensors' sweeps and the faults injected) are not
part of that record: measuring containment, and sensing at a fixed 10 Hz rate whenever the planner decides, change
nothing an exact drive does.
"""

from __future__ import annotations

import json
from pathlib import Path

from sim.parts import DriveConfig
from sim.simulator import run_drive

GOLDEN = Path(__file__).parent / "golden"
WALL_CLOCK = ("wall_s", "plan_ms", "plan_latency_ms")


def test_the_default_assembly_drives_the_pinned_drive_exactly(tmp_path: Path) -> None:
    summary = run_drive(3, DriveConfig(2.0), str(tmp_path)).to_json()
    golden = json.loads((GOLDEN / "drive-seed3-2km.json").read_text())
    assert subset(golden, summary) == golden
    assert set(summary) - set(golden) - set(WALL_CLOCK) == {"safety", "traffic_collisions", "snapshots", "restarts",
                                                            "opportunities", "decisions", "containment",
                                                            "breach_replans", "keep_lane_steps", "minimal_risk_steps",
                                                            "takeovers", "sweeps", "faults", "refusals", "shadowed",
                                                            "sensed_breaches", "unseen_breaches", "committed_parts",
                                                            "escapes", "unsafe_starts", "reference_starts",
                                                            "refined_starts", "reversed_moves",
                                                            "moves_finished", "moves_undone", "moves_unproved"}
    assert summary["traffic_collisions"] == 0 and summary["safety"]["contacts"] == 0 and summary["restarts"] == 0
    assert (tmp_path / "trace-seed3.jsonl").read_text() == (GOLDEN / "drive-seed3-2km-trace.jsonl").read_text()


def subset(golden: object, value: object) -> object:
    """``value`` cut down to the keys ``golden`` has, at every level (figures added since are left out)."""
    if isinstance(golden, dict) and isinstance(value, dict):
        return {key: subset(golden[key], value.get(key)) for key in golden}
    return value
