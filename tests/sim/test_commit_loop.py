"""The sound model's commitment semantics in the closed loop: each decision executes its committed part along the
reference proved with its escape, and a decision that proves nothing keeps the rest of the last one on that
decision's reference and clock."""

from __future__ import annotations

from dataclasses import replace
from typing import Any, cast

import pytest

from sim.containment import Containment
from sim.driver.control import Steps
from sim.driver.sound import SoundDriver
from sim.parts import DriveConfig
from sim.simulator import Simulator
from sim.summary import RunSummary
from spec.actions import ACTION_RULES, Action
from spec.errors import OptionError
from spec.escapes import Semantics
from spec.motion import SpeedProfile, action_speed_mps, plan_profiles

#: The paper's world with noisy sensing, seed 4: within its first 3 km a committed part is followed by a decision
#: that proves nothing, and the rest of the committed part and its escape are kept.
SEED = 4
KEPT = DriveConfig(3.0, model="sound", sensor="noisy", semantics=Semantics.COMMIT, restart_after_collision=True)


class Recorded(Simulator):
    """A simulator that records every proved sequence a decision executes (with its reference profiles), every
    reset of the position reference, and every run of the proved sequence kept from the last decision (its driver:
    ``RecordedDriver``)."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        #: per decision executed: its sequence, its reference's profiles, where the reference started and when
        self.sequences: list[tuple[tuple[Action, ...], list[SpeedProfile], float, float]] = []
        #: per kept plan: its actions, its profiles, whether the reference reset, how many decisions were made before
        self.kept_runs: list[tuple[tuple[Action, ...], list[SpeedProfile], bool, int]] = []
        self.ends: list[tuple[float, float]] = []  # after every action run: the position reference, and when
        self.resets = 0
        self.kept_ends: list[tuple[float, float]] = []  # each kept plan's first action's end: reference, when
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        reset, action = self.executor.reset_reference, self.executor.acting

        def counted(ahead_m: float = 0.0) -> None:
            self.resets += 1
            reset(ahead_m)

        def ran(*args: Any, **kwargs: Any) -> Steps:
            ok = yield from action(*args, **kwargs)
            self.ends.append((self.executor.x_ref_m, self.summary.sim_time_s))
            return ok

        self.executor.reset_reference = counted  # type: ignore[method-assign]
        self.executor.acting = ran  # type: ignore[method-assign]


class RecordedDriver(SoundDriver[Containment]):
    """The sound model's driver, recording on its ``Recorded`` host."""

    def execute(self, actions: tuple[Action, ...], speed_mps: float, what: str,
                escape: tuple[Action, ...] = (), on_reference: bool = False) -> Steps:
        sim = cast(Recorded, self.host)
        sequence = (*actions, *escape)
        profiles = plan_profiles(sequence, speed_mps, sim.grid, to_common=False)
        start_m = sim.executor.x_ref_m if on_reference else sim.car.pose().x_m  # where its reference starts
        sim.sequences.append((sequence, profiles, start_m, sim.summary.sim_time_s))
        return (yield from super().execute(actions, speed_mps, what, escape, on_reference))

    def keep_proved(self, why: str) -> Steps:
        sim = cast(Recorded, self.host)
        before, runs = sim.resets, len(sim.ends)
        pending, profiles = self.pending, list(self.pending_profiles)
        ok = yield from super().keep_proved(why)
        if pending:
            sim.kept_runs.append((pending, profiles, sim.resets > before, len(sim.sequences)))
            sim.kept_ends.append(sim.ends[runs])
        return ok


Recorded.driving = RecordedDriver


@pytest.fixture(scope="module")
def kept_drive() -> tuple[Recorded, RunSummary]:
    sim = Recorded(SEED, KEPT.parts(), restart_after_collision=True)
    try:
        return sim, sim.drive(KEPT.km)
    finally:
        sim.close()


def test_a_kept_escape_runs_on_the_proved_reference_of_its_decision_not_one_restarted_at_the_car(
        kept_drive: tuple[Recorded, RunSummary]) -> None:
    """The proof of a committed part and its escape is made for one reference from the snapshot, ramps between
    actions centred on their boundaries (the ramp into the escape starts inside the committed part). A decision
    that proves nothing keeps what is left of that reference: the same profiles, on the decision's clock, without
    restarting the position reference at the car (which would start the escape's ramp late: on seed 1 of this world
    it put the AV back into the left lane beside the vehicle it had dropped behind)."""
    sim, summary = kept_drive
    assert summary.escapes >= 1 and sim.kept_runs
    for (pending, profiles, reset, made), (x_ref_m, t_s) in zip(sim.kept_runs, sim.kept_ends, strict=True):
        assert not reset
        seq, prof, x0_m, t0_s = next(d for d in reversed(sim.sequences[:made])
                                     if d[0][len(d[0]) - len(pending):] == pending)
        j = len(seq) - len(pending)
        assert profiles == prof[j:]  # the tail of the decision's own reference
        # the first kept action ends where and when that reference ends it: on its place and clock, the control step
        # the decision that kept it spent planning included. The executor's reference sums each control step's speed
        # from the step's start (a ramp of dv m/s leaves it dv x dt / 2 off the profile's integral): so does this sum
        dt_s = sim.executor.dt_s
        summed_m = sum(prof[i].at(k * dt_s) * dt_s for i in range(j + 1)
                       for k in range(round(float(ACTION_RULES[seq[i]].duration_s) / dt_s)))
        duration_s = float(ACTION_RULES[seq[j]].duration_s)
        assert x_ref_m == pytest.approx(x0_m + summed_m, abs=0.1)
        assert t_s == pytest.approx(t0_s + prof[j].offset_s + duration_s, abs=1e-6)


def test_a_committed_part_ramps_into_its_escape_as_the_proof_has_it(kept_drive: tuple[Recorded, RunSummary]) -> None:
    """Where the escape is slower than the committed part's last action, that action is executed with the ramp into
    the escape already begun before their boundary (centred on it), as the proof of the two as one sequence has it."""
    sim, _ = kept_drive
    grid = KEPT.grid
    slower = [(seq, prof, k) for seq, prof, _, _ in sim.sequences for k in range(1, len(seq))
              if action_speed_mps(seq[k], grid) < action_speed_mps(seq[k - 1], grid)]
    assert slower
    for seq, prof, k in slower:
        end_s = float(ACTION_RULES[seq[k - 1]].duration_s)
        assert prof[k - 1].at(end_s - 0.05) < action_speed_mps(seq[k - 1], grid) - 0.5


def test_the_commitment_semantics_overtakes_with_nothing_hit_inside_the_assumptions(
        kept_drive: tuple[Recorded, RunSummary]) -> None:
    _, summary = kept_drive
    assert summary.overtakes >= 1 and summary.committed_parts >= 1
    assert summary.safety.count("contact", True) == 0 and summary.safety.count("near_miss", True) == 0
    assert not summary.collisions
    assert RunSummary.from_json(summary.to_json()).to_json() == summary.to_json()


def test_the_loops_semantics_is_part_of_a_drives_configuration_and_bad_input_names_the_option() -> None:
    assert DriveConfig.from_json(KEPT.to_json()) == KEPT
    assert DriveConfig(1.0, model="sound").semantics is Semantics.COMMIT  # the sound model's own way in the loop
    assert DriveConfig(1.0).semantics is Semantics.WHOLE and "semantics" not in DriveConfig(1.0).to_json()
    assert DriveConfig(1.0, model="sound", semantics="whole").semantics is Semantics.WHOLE  # type: ignore[arg-type]
    # a sound drive recorded before the loop committed planned whole plans: read back so, never mixed with commit runs
    recorded = {k: v for k, v in DriveConfig(1.0, model="sound").to_json().items() if k != "semantics"}
    assert DriveConfig.from_json(recorded).semantics is Semantics.WHOLE
    with pytest.raises(OptionError, match="needs --model sound") as paper:
        DriveConfig(1.0, semantics=Semantics.COMMIT)
    assert paper.value.key == "--semantics"
    with pytest.raises(OptionError) as bad:
        DriveConfig(1.0, model="sound", semantics="sometimes")  # type: ignore[arg-type]
    assert bad.value.key == "--semantics"
    assert replace(KEPT, semantics=Semantics.WHOLE).parts().planner.sound.commitment is None  # type: ignore[union-attr]
    assert KEPT.parts().planner.sound.commitment is not None  # type: ignore[union-attr]


def test_plans_from_the_reference_and_the_sets_the_last_proof_narrows_find_no_start_breaking_the_specification(
        ) -> None:
    """The paper's world, noisy sensing at 10.5 m, seed 2: plans start on the proved reference the car runs on, its
    AV at the reference's speed while the snapshot ages (``Sound.from_reference``), from the readings narrowed by
    the last proof's sets (``Monitor.refine``), so no start breaks the specification while that proof holds (from
    the readings alone, 1 in 7 km did: a noisy reading nearer than the proof's sets); the AV overtakes on, and
    nothing is hit inside the assumptions. A start that does break it is left, never held (``decide.choose``,
    tests/sim/driver)."""
    from sim.simulator import run_drive

    summary = run_drive(2, DriveConfig(7.0, model="sound", sensor="noisy", cell_m=10.5))
    assert summary.unsafe_starts == 0 and not summary.failures and not summary.takeovers
    assert summary.reference_starts > summary.plans / 2 and summary.overtakes > 20
    assert summary.refined_starts > summary.plans / 2
    assert summary.safety.count("contact", True) == 0 and summary.safety.count("near_miss", True) == 0


def test_an_encounter_while_a_decision_plans_is_attributed_under_the_decision_the_av_still_executes() -> None:
    """While a decision plans, the AV still executes the one before (a missed oncoming reading committed it to a
    right lane change; the next snapshot shows the vehicle): an encounter then is judged under the executing
    decision's sets, where the vehicle broke them (``appeared``), not under the sets of the snapshot that has not
    acted yet. Once that decision acts, its own sets judge."""
    from types import SimpleNamespace

    from sim.driver.monitor import Breach, BreachKind
    from sim.simulator import Simulator

    appeared = Breach(7, 9.3, 1161.0, "unknown right-lane vehicle", 12, BreachKind.APPEARED, 28.4, "right_lane_change")
    executing, planning = SimpleNamespace(breached={12: appeared}), SimpleNamespace(breached={})
    sim = SimpleNamespace(steering=SimpleNamespace(active=None), takeover=None, containment=planning,
                          previous=executing, watch=object(),
                          doing="planning (right_lane_change (plan 7, step 1 of 1))",
                          summary=SimpleNamespace(sim_time_s=1162.5), _hidden=lambda c, body: None)
    found = Simulator._attribution(sim, 12)  # type: ignore[arg-type]
    assert found == "after an assumption broke: appeared by 28.4 m, 1.5 s before"
    sim.doing = "drive (plan 8, step 1 of 2)"
    assert Simulator._attribution(sim, 12) == "inside the assumptions"  # type: ignore[arg-type]


def test_a_recentred_world_moves_every_decisions_sets_the_loop_still_reads_once_each() -> None:
    """``Simulator._recentre``: the sets of the decision under way, of the one before it (an encounter while a
    decision plans is judged under them), the last proof the driver keeps (a decision may go on under it after the
    world moved) and the paper's sighting each move with the world, once even where two are the same sets; so do the
    bodies, the references and the driver's proved reference."""
    from types import SimpleNamespace

    moved: dict[str, float] = {}

    def part(name: str) -> SimpleNamespace:
        return SimpleNamespace(shift_x=lambda dx_m: moved.__setitem__(name, moved.get(name, 0.0) + dx_m))

    current, before, sighting = part("current"), part("before"), part("sighting")
    driver = SimpleNamespace(proved=before, shift_x=part("boundary").shift_x)
    sim = SimpleNamespace(origin_km=2.0, car=part("car"), traffic=part("traffic"), tracker=part("tracker"),
                          executor=SimpleNamespace(x_ref_m=1003.0), containment=current, previous=before,
                          sighted=sighting, sound_driver=driver)
    Simulator._recentre(sim, 1001.0)  # type: ignore[arg-type]
    assert moved == dict.fromkeys(["car", "traffic", "current", "before", "sighting", "boundary", "tracker"], -1001.0)
    assert sim.origin_km == pytest.approx(3.001) and sim.executor.x_ref_m == pytest.approx(2.0)
    driver.proved, moved = part("kept"), {}
    Simulator._recentre(sim, 1001.0)  # type: ignore[arg-type]
    assert moved["kept"] == moved["before"] == -1001.0
