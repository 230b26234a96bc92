"""The sound model in the closed loop: plans from the car's measured speed, containment every control step, no
decision kept past a breach the AV senses, the fallback when the world breaks the assumptions, every encounter
attributed."""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import pytest

from sim.parts import DriveConfig
from sim.simulator import Simulator, run_drive
from sim.summary import RunSummary
from sim.tolerance import ToleranceReport
from spec.errors import OptionError
from spec.physical import LOOP, SENSORS
from tests.sim.test_pinned_drive import WALL_CLOCK


class Watched(Simulator):
    """A simulator that checks, on every control step, that no action of a sound decision runs on after a breach the
    AV sensed for longer than one control step and a sideways move; and how long after the truth's breach the AV
    sensed one."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.first_breach: dict[int, float] = {}  # decision -> when the AV sensed a breach of its assumptions
        self.longest_s = 0.0
        self.truth_first: dict[int, float] = {}  # decision -> when a vehicle broke them (the truth)
        self.lags_s: list[float] = []  # per decision breached in both: sensed minus true
        self.in_lane_s: list[float] = []  # the same, at each step of an action in lane (no sideways move to finish)

    def _tick(self, dt_s: float) -> bool:
        ok = super()._tick(dt_s)
        c = self.containment
        if c is not None and c.world_breached():
            self.truth_first.setdefault(c.decision, self.summary.sim_time_s)
        if c is not None and c.sensed is not None and self.enveloped:
            since = self.first_breach.setdefault(c.decision, c.sensed.t_s)
            self.longest_s = max(self.longest_s, self.summary.sim_time_s - since)
            if not self.doing.startswith(("right_lane_change", "left_lane_change")):
                self.in_lane_s.append(self.summary.sim_time_s - since)
            if c.decision in self.truth_first and len(self.lags_s) < len(self.first_breach):
                self.lags_s.append(since - self.truth_first[c.decision])
        return ok


def drive(config: DriveConfig, seed: int) -> tuple[Watched, RunSummary]:
    sim = Watched(seed, config.parts(), restart_after_collision=True, snapshots=config.snapshots)
    try:
        return sim, sim.drive(config.km)
    finally:
        sim.close()


def test_sound_plans_start_from_the_cars_measured_speed_and_nothing_inside_the_assumptions_is_hit() -> None:
    _, summary = drive(DriveConfig(1.0, model="sound", snapshots=50), 3)
    assert summary.plans > 0 and summary.snapshots
    speeds = [s["bounds"]["av_speed_mps"] for s in summary.snapshots]
    assert len(set(speeds)) > 1  # the measured speed, not the common speed
    assert summary.safety.count("contact", True) == 0 and summary.safety.count("near_miss", True) == 0
    assert RunSummary.from_json(summary.to_json()).to_json() == summary.to_json()


#: Vehicles that stop (too slow by far), seed 2: one drive, watched and traced, that the two tests below read.
STOPPING = DriveConfig(1.0, model="sound", traffic="spread", stop_rate_per_h=300.0, restart_after_collision=True)


@pytest.fixture(scope="module")
def stopping(tmp_path_factory: pytest.TempPathFactory) -> tuple[Watched, RunSummary, Path]:
    """The drive of ``STOPPING`` as ``sim.simulator.run_drive`` assembles it, watched, its trace in the folder."""
    from sim.observers import TraceWriter

    folder = tmp_path_factory.mktemp("stopping")
    with (folder / "trace-seed2.jsonl").open("w") as trace:
        sim = Watched(2, STOPPING.parts((TraceWriter(trace),)), STOPPING.replan_on_violation,
                      ToleranceReport(STOPPING.step_tolerance_cells, STOPPING.plan_tolerance_cells), None,
                      STOPPING.snapshots, STOPPING.restart_after_collision, STOPPING.opportunity_checks)
        try:
            summary = sim.drive(STOPPING.km)
        finally:
            sim.close()
    return sim, summary, folder


@pytest.mark.xdist_group("stopping")  # the tests reading one drive run on one worker, which drives it once
def test_no_sound_decision_runs_on_past_a_sensed_breach_and_a_broken_world_is_counted(
        stopping: tuple[Watched, RunSummary, Path]) -> None:
    """Vehicles that stop (too slow by far): the truth's breaches are counted, the AV senses them from its sweeps and
    ends its decision within a control step and a sideways move of that (an action in lane: by the next sweep), and
    it senses them no sooner than they happen (the monitor reads no truth)."""
    sim, summary, _ = stopping
    assert summary.containment.by_kind.get("too slow", 0) > 0
    assert summary.sensed_breaches > 0 and summary.breach_replans + len(summary.takeovers) > 0
    assert sim.longest_s <= LOOP.lane_change_lateral_s + 2 * sim.executor.dt_s
    # an action in lane ends at the first sweep after it (measured before: up to the 2 s a sideways move takes, seed
    # 55 of the 2,000 km following audit braked on at 3.5 m/s for 1.4 s after it sensed a stopped vehicle ahead)
    assert sim.in_lane_s and max(sim.in_lane_s) <= 1 / SENSORS.sweep_hz + 2 * sim.executor.dt_s
    assert sim.lags_s and min(sim.lags_s) >= 0.0


def test_a_sensor_noisier_than_its_bound_is_a_breach_the_av_finds_in_its_sweeps_not_at_the_snapshot() -> None:
    """Sensing noise 3 m against the bounds' 1.5 m error: the truth shows readings off by more than the bound at the
    snapshot itself (bookkeeping: ``sensing error``); the AV cannot know a snapshot wrong, but the sweeps after it
    disagree with the sets made from it by more than twice the bound, and those end its decisions."""
    _, summary = drive(DriveConfig(2.0, model="sound", sensor="noisy", range_sd_m=3.0), 20261126)
    at_snapshot = [b for b in summary.containment.breaches if b.kind.value in ("sensing error", "appeared")]
    assert at_snapshot and summary.sensed_breaches > 0 and summary.breach_replans > 0


def test_paper_model_drives_measure_containment_without_acting_on_it() -> None:
    _, summary = drive(DriveConfig(1.0, traffic="spread", stop_rate_per_h=300.0), 2)
    assert summary.decisions > 0 and summary.containment.checked_s > 0
    assert summary.breach_replans == summary.keep_lane_steps == summary.minimal_risk_steps == 0
    assert not summary.takeovers


def test_a_models_name_and_bounds_scale_are_part_of_a_drives_configuration() -> None:
    config = DriveConfig(1.0, model="sound", bounds_scale=2.0)
    assert DriveConfig.from_json(config.to_json()) == config
    assert "model" not in DriveConfig(1.0).to_json()  # records of the paper model stay the same campaign
    spread = DriveConfig(1.0, traffic="spread")
    assert replace(spread, bounds_scale=2.0).bounds.same_mps.high_mps > spread.bounds.same_mps.high_mps
    for bad in ({"model": "nosuch"}, {"bounds_scale": -1.0}, {"bounds_scale": float("nan")}):
        with pytest.raises(OptionError):
            DriveConfig(1.0, **bad)  # type: ignore[arg-type]


def test_the_lead_is_the_nearest_vehicle_ahead_and_its_closing_speed_is_fitted_only_on_the_same_one() -> None:
    from sim.nearest import Nearest as Lead
    from sim.sensors import Reading
    from spec.envelope import MINIMAL_RISK
    from spec.lanes import Lane

    sweep = (Reading(Lane.LEFT, 1, 30.0), Reading(Lane.LEFT, 2, 9.0), Reading(Lane.LEFT, 3, -8.0),
             Reading(Lane.RIGHT, 4, 5.0))
    first = Lead.after(None, sweep, 10.0)
    assert first == Lead(9.0, None, (9.0,))
    closer = Lead.after(first, (Reading(Lane.LEFT, 2, 8.5),), 10.0)
    assert closer is not None and closer.dx_m == 8.5 and closer.measured_mps is None  # two readings: not measured
    closer = Lead.after(closer, (Reading(Lane.LEFT, 2, 8.0),), 10.0)
    assert closer is not None and closer.measured_mps == pytest.approx(5.0)
    assert Lead.after(closer, (Reading(Lane.LEFT, 1, 29.5),), 10.0) == Lead(29.5, None, (29.5,))  # another vehicle
    assert Lead.after(closer, None, 10.0) is None  # a dropped sweep: nothing sensed
    assert Lead.after(closer, (Reading(Lane.LEFT, 3, -7.0),), 10.0) is None  # nothing ahead
    lead = None
    for k in range(3 * MINIMAL_RISK.fit_sweeps):
        lead = Lead.after(lead, (Reading(Lane.LEFT, 2, 20.0 - 0.3 * k),), 10.0)
    assert lead is not None and len(lead.distances_m) == MINIMAL_RISK.fit_sweeps
    assert lead.measured_mps == pytest.approx(3.0)


def test_the_fallbacks_closing_speeds_take_the_avs_own_speed_changes_out_and_follow_its_speed_between_sweeps(
        ) -> None:
    """The AV speeds up at 2.7 m/s2 from 8.5 m/s behind a vehicle at 7 m/s (seed 48 of the reliability campaign at
    c2c5ab8, whose fit said 2.2 m/s closing where it was 2.8, and whose return came within 0.6 m of it), with a
    vehicle behind at 7 m/s: at each sweep the closing speeds are the true ones at the AV's speed then, and between
    sweeps they move with the AV's speed; the vehicles' own speeds stay 7 m/s."""
    from sim.nearest import Nearest
    from sim.sensors import Reading
    from spec.envelope import MINIMAL_RISK
    from spec.lanes import Lane

    lead = follower = None
    for k in range(2 * MINIMAL_RISK.fit_sweeps):
        t = k / 10.0
        av_m, av_mps = 8.5 * t + 2.7 * t * t / 2, 8.5 + 2.7 * t
        sweep = (Reading(Lane.LEFT, 1, 30.0 + 7.0 * t - av_m), Reading(Lane.LEFT, 2, -20.0 + 7.0 * t - av_m))
        lead = Nearest.after(lead, sweep, 10.0, travelled_m=1000.0 + av_m, av_mps=av_mps)
        follower = Nearest.after(follower, sweep, 10.0, behind=True, travelled_m=1000.0 + av_m, av_mps=av_mps)
        if k >= 2:
            assert lead is not None and lead.measured_mps == pytest.approx(av_mps - 7.0, abs=1e-6)
            assert follower is not None and follower.measured_mps == pytest.approx(7.0 - av_mps, abs=1e-6)
    assert lead is not None and follower is not None
    later_mps = av_mps + 0.27  # a tenth of a second on
    assert lead.closing_now_mps(later_mps) == pytest.approx(later_mps - 7.0, abs=1e-6)
    assert follower.closing_now_mps(later_mps) == pytest.approx(7.0 - later_mps, abs=1e-6)
    assert lead.own_mps(later_mps) == pytest.approx(7.0) and follower.own_mps(later_mps) == pytest.approx(7.0)
    assert lead.closing_mps(later_mps) == pytest.approx(later_mps - 7.0, abs=1e-6)
    # in a sideways move the fit takes the AV's speed along the road; a change after the sweep, along its heading
    yawed = None
    for k in range(4):
        yawed = Nearest.after(yawed, (Reading(Lane.LEFT, 1, 20.0 + (7.0 - 9.9) * k / 10.0),), 10.0,
                              travelled_m=9.9 * k / 10.0, av_mps=10.0, along_mps=9.9)
    assert yawed is not None and yawed.measured_mps == pytest.approx(9.9 - 7.0, abs=1e-6)
    assert yawed.closing_now_mps(10.5) == pytest.approx(9.9 - 7.0 + 0.5, abs=1e-6)
    # without the AV's odometer (the tests' views): the distances' own fit, at the speed asked about
    plain = Nearest(12.0, 2.0)
    assert plain.closing_now_mps(9.0) == 2.0 and plain.own_mps(9.0) == 7.0


@pytest.mark.slow  # 3 to 22 km of drives with the paper's faults and tracking: .ci/run runs them
@pytest.mark.parametrize(("seed", "km"), [(6, 3.0), (4, 22.0), (12, 17.0)])
def test_the_fallback_neither_brakes_below_traffic_that_keeps_its_speed_nor_returns_into_it(seed: int,
                                                                                            km: float) -> None:
    """The paper's world with its faults and tracking (seeds 4 and 6 of the evaluation): the fallback took over
    after vehicles appeared; braking for a standstill ahead that was not there, it was run into by a follower that
    never brakes (seed 6, 2.5 km), and returning from the right lane at 13 m/s it ran into the vehicle ahead, or
    beside it (seed 4, 21 km). Now it brakes for the closing speed it measures and returns only into room. Braking in
    lane behind a vehicle at its measured speed, the car ran 0.17 m/s above its command and crept into it (seed 12,
    15.5 km): it now brakes on while the gap still closes. Then it held that gap, 2 m behind the vehicle ahead and
    10 m before the one behind, where no decision found a safe step: 1,648 take-overs in a row from 15.4 km. It now
    opens the gap towards the middle of its slot, for the speed it hands back at, and no decision is left without
    a safe step in lane for long: a few such take-overs, each handed back, never three within a kilometre (seed 4's
    four in the right lane, since the AV's own monitor decides on what it senses: one found no plan where a fault
    showed what the truth did not)."""
    summary = run_drive_summary(seed, km)
    assert summary.failure is None, (seed, summary.failure)
    stuck = [t for t in summary.takeovers if t.cause.endswith("no safe step in lane")]
    assert all(t.outcome == "handed back" for t in stuck), (seed, stuck)
    # a loop takes over again at once, one take-over (``takeover_s``) after the other: 1,648 in 35 km; here
    # (seed 4) 4 in 22 km, the nearest two 1.4 km apart
    crowded = [kms for kms in zip(*(tuple(t.km for t in stuck[k:]) for k in range(3))) if kms[2] - kms[0] < 1.0]
    assert not crowded, (seed, crowded[:1])
    if seed == 4:
        assert summary.takeovers  # the fallback did act (seed 6 no longer needs it by 3 km: the shadowed oncoming lane)


def run_drive_summary(seed: int, km: float) -> RunSummary:
    from sim.simulator import run_drive

    return run_drive(seed, DriveConfig(km, until_failure=True, faults="paper", tracking=True, model="sound"))


def test_the_follower_and_the_oncoming_vehicle_are_the_nearest_behind_and_ahead_in_their_lanes() -> None:
    from sim.nearest import Nearest
    from sim.sensors import Reading
    from spec.lanes import Lane

    follower = oncoming = None
    for k in range(4):  # a follower 20 m behind closing at 2 m/s; an oncoming vehicle 200 m ahead closing at 14
        sweep = (Reading(Lane.LEFT, 1, -20.0 + 0.2 * k), Reading(Lane.LEFT, 2, -60.0), Reading(Lane.LEFT, 3, 30.0),
                 Reading(Lane.RIGHT, 4, 200.0 - 1.4 * k), Reading(Lane.RIGHT, 5, -10.0))
        follower = Nearest.after(follower, sweep, 10.0, behind=True)
        oncoming = Nearest.after(oncoming, sweep, 10.0, Lane.RIGHT)
    assert follower is not None and follower.dx_m == pytest.approx(19.4)
    assert follower.measured_mps == pytest.approx(2.0)
    assert oncoming is not None and oncoming.dx_m == pytest.approx(195.8)
    assert oncoming.measured_mps == pytest.approx(14.0)


def _fallback_view(follower: object, oncoming: object, react: bool, sweep: object = ()) -> object:
    from types import SimpleNamespace

    return SimpleNamespace(follower=follower, oncoming=oncoming, sweep=sweep,
                           watch=SimpleNamespace(bounds=SimpleNamespace(followers_react=react,
                                                                        oncoming_mps=SimpleNamespace(high_mps=9.0))))


@pytest.mark.parametrize(("gap_m", "closing_mps", "react", "blocks"),
                         [(30.0, 1.0, False, False), (3.0, 1.0, False, True), (3.0, 1.0, True, False),
                          (30.0, None, False, True), (30.0, 2.0, False, True), (30.0, 12.0, False, True)])
def test_a_follower_that_keeps_its_speed_blocks_the_return_while_nearer_than_the_specification_allows(
        gap_m: float, closing_mps: float | None, react: bool, blocks: bool) -> None:
    """Seeds 6 and 8 of the faults evaluation (paper traffic, whose followers never brake): the fallback returned
    from the right lane slower than the vehicle behind and was rear-ended; seed 21 of the reliability campaign: 31 m
    ahead of one closing at 6.8 m/s (the gap enough for the lane change's 3 s) it returned from a standstill, and the
    sideways move took 5 s. A follower closing faster than the fit's error (``MinimalRisk.open_mps``) blocks."""
    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.physical import CAR

    follower = Nearest(gap_m + CAR.length_m, closing_mps)
    assert Simulator._follower_blocks(_fallback_view(follower, None, react), 2.0, 8.0) is blocks  # type: ignore[arg-type]


def test_the_fallback_passing_a_vehicle_beside_it_is_held_back_only_by_a_gap_ahead_that_breaks_the_spec_now(
        ) -> None:
    """Seed 22 of the reliability campaign: in the right lane, 3.6 m ahead of a vehicle it was passing, the fallback
    matched the speed of a "vehicle ahead" (a fake gap's copy) 20 m on, because a return would have left too small a
    gap to it, and stayed beside the vehicle until the oncoming one left no time. Passing, the AV stays at least
    ``open_mps`` faster than the vehicle beside it while the gap ahead meets the specification now."""
    from types import SimpleNamespace

    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.envelope import MINIMAL_RISK
    from spec.physical import CAR
    from spec.safety import SAFETY

    beside = Nearest(3.6, -1.0, behind=True)  # 3.6 m behind the AV's centre, the AV 1 m/s the faster

    def target(lead: Nearest, follower: Nearest = beside) -> float | None:
        view = SimpleNamespace(lead=lead, follower=follower)
        return Simulator._waiting_mps(view, 8.0, True, True, False)  # type: ignore[arg-type]

    closing = 2.0  # on the vehicle ahead, at 6 m/s
    far = Nearest(SAFETY.required_gap_m(closing) + CAR.length_m + 5.0, closing)
    assert target(far) == pytest.approx(7.0 + MINIMAL_RISK.open_mps)  # on past it
    assert target(far, Nearest(3.6, 2.0, behind=True)) == pytest.approx(6.0)  # the one beside the faster: no pass
    near = Nearest(SAFETY.required_gap_m(closing) + CAR.length_m - 0.5, closing)
    assert target(near) == pytest.approx(6.0)  # the gap ahead too small now: its speed


def test_the_fallback_drops_back_behind_a_vehicle_beside_it_at_that_vehicles_speed_not_to_a_standstill() -> None:
    """Seed 38 of the reliability campaign (48254f9): a reading beside the AV in the left lane, 0.9 m ahead of its
    centre and moving away at 2.7 m/s, became the vehicle ahead; the fallback's target was ``open_mps`` below the
    AV's own speed, every control step, so it braked from 4.4 m/s to a standstill in the right lane while an oncoming
    vehicle closed, and the forced return later cut in front of a follower. Beside a vehicle it is not faster than,
    it now drives ``open_mps`` below that vehicle's speed."""
    from types import SimpleNamespace

    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.envelope import MINIMAL_RISK

    view = SimpleNamespace(lead=Nearest(0.9, -2.7), follower=None)
    target = Simulator._waiting_mps(view, 4.0, True, False, False)  # type: ignore[arg-type]
    assert target == pytest.approx(4.0 + 2.7 - MINIMAL_RISK.open_mps)
    view = SimpleNamespace(lead=Nearest(0.9, 0.0), follower=None)  # at the AV's speed: below it
    assert Simulator._waiting_mps(view, 4.0, True, False, False) == pytest.approx(  # type: ignore[arg-type]
        4.0 - MINIMAL_RISK.open_mps)


def test_the_fallback_beside_a_vehicle_it_is_faster_than_drops_back_or_passes_whichever_ends_sooner() -> None:
    """Seed 51 of the 1,000 km campaign (8a81810): waiting in the right lane at 8.19 m/s behind a left-lane vehicle
    at 7.0 m/s whose gap had fallen to 1.25 m (below the least gap), the fallback had no rule for a vehicle ahead it
    is the faster of, kept its speed and crept alongside at 1.2 m/s (a 10 s pass) until the oncoming vehicle (73 m,
    closing at 15.2 m/s) forced a return into it. It now drops back, ``open_mps`` below that vehicle's speed, when
    that ends sooner than the pass (about 1 s here); 5 m/s the faster and nearly level, it passes on (1.4 s against
    6 s); beside a vehicle standing it cannot drop back and passes; with the vehicle's speed not measured, it keeps
    its own."""
    from types import SimpleNamespace

    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.envelope import MINIMAL_RISK as mr
    from spec.physical import CAR

    def target(lead: Nearest, speed_mps: float = 8.19, follower: Nearest | None = None) -> float | None:
        return Simulator._waiting_mps(SimpleNamespace(lead=lead, follower=follower),  # type: ignore[arg-type]
                                      speed_mps, True, follower is not None and follower.gap_m < 2.0, False)

    assert target(Nearest(1.25 + CAR.length_m, 8.19 - 7.0)) == pytest.approx(7.0 - mr.open_mps)
    assert target(Nearest(-0.5 + CAR.length_m, 8.19 - 7.0)) == pytest.approx(7.0 - mr.open_mps)
    assert target(Nearest(1.25 + CAR.length_m, None)) is None  # not measured: the speed it has
    assert target(Nearest(0.5, 5.0), speed_mps=12.0) == 12.0  # passing ends sooner: the speed it has, 5 m/s faster
    assert target(Nearest(5.0, 1.0), speed_mps=1.0) == mr.open_mps  # beside a vehicle standing: it passes
    assert mr.pass_s(1.19, 1.25 + CAR.length_m) == pytest.approx(8.2, abs=0.1)  # up to 1.5 m/s the faster
    assert mr.drop_back_s(1.19, 1.25 + CAR.length_m, 7.0) == pytest.approx(0.9, abs=0.1)
    assert mr.pass_s(5.0, 0.5) == pytest.approx(1.4) and mr.drop_back_s(5.0, 0.5, 7.0) == pytest.approx(6.35, abs=0.05)
    assert mr.pass_s(0.0, 0.5) == pytest.approx(4.94, abs=0.01) and mr.drop_back_s(1.0, 5.0, 0.0) == math.inf
    # a vehicle alongside behind, 2.5 m behind the AV's centre and 4 m behind the one ahead's: no slot between them;
    # a drop back ends behind it too (6.7 s), longer than passing the one ahead (5.25 s)
    behind = Nearest(2.5, -2.0, behind=True)  # at 7 m/s
    assert target(Nearest(4.0, 2.0), speed_mps=9.0, follower=behind) == pytest.approx(9.0)  # on past both
    # a vehicle 9.5 m behind the AV, 13.5 m behind the one ahead: room for the AV between them, it drops back into it
    assert target(Nearest(4.0, 0.5), speed_mps=7.5, follower=Nearest(9.5, -0.5, behind=True)) == pytest.approx(
        7.0 - mr.open_mps)


def test_the_fallback_beside_a_vehicle_alongside_behind_passes_it_when_that_ends_sooner_and_leaves_it_room() -> None:
    """Seed 69 of the 1,000 km campaign (94bbc05): waiting in the right lane at 6.96 m/s beside a left-lane vehicle
    whose centre was 6.0 m behind the AV's (0.5 m short of clear) and 0.04 m/s the faster, with the vehicle ahead
    15 m on, the fallback dropped back behind it (``open_mps`` below its speed), 12.5 m at the speeds it ran; 6 s
    later the oncoming lane forced the return while that vehicle was still beside it, and the two touched. Passing
    it, speeding up to ``open_mps`` the faster, ends in 0.6 s against 8.5 s, and the slot ahead of it takes the AV:
    it passes. With no slot (the vehicle ahead 6.9 m on, or 11 m on and not measured: it may stand), or level with
    the vehicle, it drops back; the faster of the two, it passes whatever comes."""
    from types import SimpleNamespace

    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.envelope import MINIMAL_RISK as mr

    ahead = Nearest(14.99, -0.04)  # at 7.0 m/s

    def target(follower: Nearest, lead: Nearest | None = ahead) -> float | None:
        view = SimpleNamespace(lead=lead, follower=follower)
        return Simulator._waiting_mps(view, 6.96, False, True, True)  # type: ignore[arg-type]

    beside = Nearest(6.01, 0.04, behind=True)  # at 7.0 m/s
    assert mr.pass_s(-0.04, -6.01) == pytest.approx(0.62, abs=0.01)
    assert mr.drop_back_s(-0.04, -6.01, 7.0) == pytest.approx(8.46, abs=0.01)
    assert target(beside) == pytest.approx(7.0 + mr.open_mps)  # on past it
    assert target(beside, lead=None) == pytest.approx(7.0 + mr.open_mps)  # nothing ahead: room
    assert target(beside, lead=Nearest(6.9, -0.04)) == pytest.approx(7.0 - mr.open_mps)  # no slot: drops back
    assert target(beside, lead=Nearest(11.0, -0.04)) == pytest.approx(7.0 + mr.open_mps)  # 11 m on at 7 m/s: room
    assert target(beside, lead=Nearest(11.0, None)) == pytest.approx(7.0 - mr.open_mps)  # it may stand: none
    level = Nearest(0.0, 0.04, behind=True)  # level with the AV: passing takes 4.63 s, dropping back 4.45 s
    assert target(level) == pytest.approx(7.0 - mr.open_mps)
    assert target(Nearest(0.3, 0.04, behind=True)) == pytest.approx(7.0 + mr.open_mps)  # 4.43 s against 4.65 s
    # the AV the faster, it passes at least ``open_mps`` the faster
    assert target(Nearest(6.01, -1.0, behind=True)) == pytest.approx(5.96 + mr.open_mps)
    assert target(Nearest(6.01, -2.0, behind=True), lead=Nearest(6.9, -0.04)) == pytest.approx(6.96)


def test_a_return_that_would_end_too_near_the_vehicle_ahead_brakes_to_its_speed_from_its_start() -> None:
    """Seed 23 (the code of 4952935): the oncoming lane forced the return while the vehicle ahead in the left lane was
    5.1 m away closing at 3 m/s; the return ran at constant speed into it. A return that would end nearer the vehicle
    ahead than the specification allows brakes from its start, at the car's limit, to that vehicle's speed (not
    fitted yet: the slowest the bounds let it be)."""
    from types import SimpleNamespace

    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.actions import ACTION_RULES, Action
    from spec.envelope import MINIMAL_RISK, TRACKING
    from spec.physical import CAR
    from spec.safety import SAFETY

    change_s = float(ACTION_RULES[Action.LEFT_LANE_CHANGE].duration_s)

    slowest_mps = 4.9
    watch = SimpleNamespace(bounds=SimpleNamespace(same_mps=SimpleNamespace(low_mps=slowest_mps)))

    def profile(lead: Nearest | None, speed_mps: float = 10.0):  # type: ignore[no-untyped-def]
        car = SimpleNamespace(pose=lambda: SimpleNamespace(speed_mps=speed_mps))
        return Simulator._return_profile(SimpleNamespace(lead=lead, car=car, watch=watch,  # type: ignore[arg-type]
                                                         follower=None))

    assert profile(None).at(change_s) == pytest.approx(10.0)  # nothing ahead: the speed it starts at
    closing = 3.0
    # room at its end, the car's envelope taken (``MinimalRisk.too_near_after``): as before
    envelope_m = TRACKING.position_m
    room = Nearest(SAFETY.required_gap_m(closing + TRACKING.speed_mps) + closing * change_s + envelope_m
                   + CAR.length_m + 0.5, closing)
    assert profile(room).at(change_s) == pytest.approx(10.0)
    # room only for a car exactly on its reference: brakes
    assert profile(Nearest(SAFETY.required_gap_m(closing) + closing * change_s + CAR.length_m + 0.5,
                           closing)).at(change_s) == pytest.approx(7.0)
    near = Nearest(5.1 + CAR.length_m, closing)
    braking = profile(near)
    assert braking.at(0.0) == pytest.approx(10.0)
    assert braking.at(change_s) == pytest.approx(7.0)  # the vehicle ahead's speed
    assert braking.at(closing / MINIMAL_RISK.emergency_decel_mps2) == pytest.approx(7.0)  # at the car's limit
    # its speed not fitted yet: the slowest the bounds let it be, not a standstill (seeds 13 and 16 at 6994c0a: the AV
    # stood across the lanes and the vehicle it had passed ran into it)
    assert profile(Nearest(5.1 + CAR.length_m, None)).at(change_s) == pytest.approx(slowest_mps)
    unfitted_room = SAFETY.required_gap_m(10.0 - slowest_mps + TRACKING.speed_mps) + (10.0 - slowest_mps) * change_s \
        + envelope_m + CAR.length_m + 0.5
    assert profile(Nearest(unfitted_room, None)).at(change_s) == pytest.approx(10.0)
    assert profile(Nearest(5.1 + CAR.length_m, -1.0)).at(change_s) == pytest.approx(10.0)  # moving away: no brake


def test_a_forced_return_passing_a_vehicle_alongside_brakes_for_the_one_ahead_only_once_clear_of_it() -> None:
    """Seed 49 of the 1,000 km campaign at c2c5ab8 (976.1 km): forced back by an oncoming vehicle while 1.3 m ahead
    of the vehicle it was passing at 6.1 m/s more, the return braked at once to the speed of the vehicle ahead, held
    the AV beside the one it passed through the sideways move, and the two collided. Now it holds its speed until
    that vehicle is the specification's least gap behind, if that comes by the middle of the sideways move and
    braking then still stops short of the vehicle ahead; otherwise it brakes at once, as before."""
    from types import SimpleNamespace

    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.envelope import MINIMAL_RISK, TRACKING
    from spec.physical import CAR
    from spec.safety import SAFETY

    watch = SimpleNamespace(bounds=SimpleNamespace(same_mps=SimpleNamespace(low_mps=4.9)))
    speed, closing = 12.56, 6.1
    car = SimpleNamespace(pose=lambda: SimpleNamespace(speed_mps=speed))
    lead = Nearest(19.74, closing)
    beside = Nearest(1.26, -closing, behind=True)  # its centre 1.26 m behind the AV's, the AV 6.1 m/s the faster

    def profile(follower: Nearest | None, ahead: Nearest = lead):  # type: ignore[no-untyped-def]
        view = SimpleNamespace(lead=ahead, car=car, watch=watch, follower=follower)
        return Simulator._return_profile(view)  # type: ignore[arg-type]

    clear_s = (SAFETY.min_gap_m - (1.26 - CAR.length_m)) / closing
    assert clear_s <= TRACKING.lateral_s / 2
    brake_s = closing / MINIMAL_RISK.emergency_decel_mps2
    held = profile(beside)
    assert held.at(clear_s) == pytest.approx(speed)  # the speed it starts at until clear of the vehicle beside
    assert held.at(clear_s + brake_s) == pytest.approx(speed - closing)  # then the vehicle ahead's speed
    closed_m = held.distance_m(clear_s + brake_s) - (speed - closing) * (clear_s + brake_s)
    assert closed_m <= lead.gap_m - SAFETY.min_gap_m - TRACKING.position_m + 1e-9  # still short of it, with margin
    assert profile(None).at(brake_s) == pytest.approx(speed - closing)  # nothing beside: at once, as before
    slower = Nearest(1.26, closing, behind=True)  # the vehicle beside the faster: it passes, the AV brakes at once
    assert profile(slower).at(brake_s) == pytest.approx(speed - closing)
    # not clear by the middle of the sideways move (level with it, 0.5 m/s the faster): braking at once drops the AV
    # behind it, holding would keep it beside it in the lane
    level = Nearest(0.0, -0.5, behind=True)
    assert profile(level).at(brake_s) == pytest.approx(speed - closing)
    # the vehicle ahead too near to wait until clear: at once
    tight = Nearest(CAR.length_m + SAFETY.min_gap_m + TRACKING.position_m + closing * brake_s / 2 + closing * clear_s
                    - 0.1, closing)
    assert profile(beside, tight).at(brake_s) == pytest.approx(speed - closing)


def test_the_fallback_waits_in_the_right_lane_only_while_the_oncoming_lane_leaves_time() -> None:
    from sim.nearest import Nearest
    from sim.simulator import Simulator
    from spec.envelope import TRACKING
    from spec.physical import CAR
    from spec.safety import SAFETY

    def leaves(oncoming: object, sweep: object = ()) -> bool:
        return Simulator._oncoming_leaves_time(_fallback_view(None, oncoming, False, sweep), 2.0,  # type: ignore[arg-type]
                                               7.0)

    def need(closing_mps: float) -> float:  # the return's prediction takes the car's envelope (``too_near_after``)
        return SAFETY.required_gap_m(closing_mps + TRACKING.speed_mps) + closing_mps * 2.1 + TRACKING.position_m \
            + CAR.length_m

    closing = 14.0
    need_m = need(closing)
    assert leaves(None)  # none sensed within the front-right sensor's range
    assert not leaves(None, sweep=None)  # a dropped sweep
    assert leaves(Nearest(need_m + 1.0, closing)) and not leaves(Nearest(need_m - 1.0, closing))
    # its speed not measured yet (its first two sweeps): the AV's 7 m/s and the bounds' fastest oncoming speed
    unmeasured = 7.0 + 9.0
    need_m = need(unmeasured)
    assert leaves(Nearest(need_m + 1.0, None)) and not leaves(Nearest(need_m - 1.0, None))


def test_the_fallbacks_wait_in_the_right_lane_ends_as_soon_as_a_sensed_oncoming_vehicle_leaves_no_time() -> None:
    """Seed 25 of the reliability campaign (1153285): a fake gap's copy beside the AV held the fallback in the right
    lane for a least wait of ``takeover_s`` while an oncoming vehicle closed from 49 m; the return began 8.6 m from
    it. A sensed oncoming vehicle now ends the wait from its start; a dropped sweep (nothing seen) only after
    ``takeover_s``; nothing holds it past ``return_wait_s``."""
    from spec.envelope import MINIMAL_RISK as mr

    early = 0.1
    assert mr.ends_wait(early, swept=True, oncoming_leaves_time=False)
    assert not mr.ends_wait(early, swept=True, oncoming_leaves_time=True)
    assert not mr.ends_wait(early, swept=False, oncoming_leaves_time=False)
    assert mr.ends_wait(mr.takeover_s + early, swept=False, oncoming_leaves_time=False)
    assert not mr.ends_wait(mr.return_wait_s, swept=True, oncoming_leaves_time=True)
    assert mr.ends_wait(mr.return_wait_s + early, swept=True, oncoming_leaves_time=True)


class Timed(Simulator):
    """A simulator that records, for every sound decision, how long after its snapshot it acted."""

    def __init__(self, *args: object, **kwargs: object) -> None:
        super().__init__(*args, **kwargs)  # type: ignore[arg-type]
        self.waits_s: list[float] = []

    def _sound_choice(self, *args: object) -> Callable[[], bool]:
        act = super()._sound_choice(*args)  # type: ignore[arg-type]
        taken_s = self.summary.sim_time_s

        def timed() -> bool:
            self.waits_s.append(self.summary.sim_time_s - taken_s)
            return act()
        return timed


def test_a_sound_decision_acts_one_control_step_after_its_snapshot_and_plans_for_that_age() -> None:
    """The planner's time counts in simulated time: the world moves on for the loop's budget before a decision acts,
    and the sound model plans with that latency in its bounds; containment measures the world from the snapshot,
    without it."""
    config = DriveConfig(0.5, model="sound", snapshots=5)
    sim = Timed(3, config.parts(), snapshots=config.snapshots)
    try:
        summary = sim.drive(config.km)
    finally:
        sim.close()
    assert sim.waits_s and all(w == pytest.approx(LOOP.plan_budget_s, abs=1e-6) for w in sim.waits_s)
    assert LOOP.plan_budget_s == pytest.approx(LOOP.physics_dt_s * LOOP.control_every_steps)  # at the next step
    assert summary.snapshots and all(s["bounds"]["latency_s"] == LOOP.plan_budget_s for s in summary.snapshots)
    assert sim.watch is not None and sim.watch.bounds.latency_s == 0.0


@pytest.mark.xdist_group("stopping")
def test_a_sound_drive_traces_every_action_and_every_fallback_and_plots_them(
        stopping: tuple[Watched, RunSummary, Path], tmp_path: Path) -> None:
    """The sound model predicts no cells, but its trace still has a line per executed action and per take-over
    (action null, what it did and for how long), so a drive's lead-up to an encounter can be read and plotted."""
    import json

    from sim.report import plot_trace

    _, summary, folder = stopping
    config = STOPPING
    records = [json.loads(line) for line in (folder / "trace-seed2.jsonl").read_text().splitlines()]
    actions = [r for r in records if r["action"] is not None]
    fallbacks = [r for r in records if r["action"] is None]
    assert summary.takeovers and len(fallbacks) == len(summary.takeovers) + summary.minimal_risk_steps
    assert len(actions) >= summary.actions > 0  # an action a collision ended is traced, not counted
    assert all(r["predicted"] is None and r["doing"] and r["duration_s"] > 0 for r in records)
    assert all(r["doing"].startswith("fallback (") for r in fallbacks)
    assert [r["t_s"] for r in records] == sorted(r["t_s"] for r in records)
    png = plot_trace(folder / "trace-seed2.jsonl", tmp_path / "spacetime-seed2.png", config.grid)
    assert png.stat().st_size > 0


def test_planning_is_named_once_in_what_the_av_was_doing_however_many_decisions_did_nothing() -> None:
    from types import SimpleNamespace

    from sim.simulator import Simulator

    held: list[float] = []
    sim = SimpleNamespace(doing="brake (plan 3, step 1 of 2)", _tick=None,
                          executor=SimpleNamespace(v_ref_mps=7.0, hold=lambda s, v, tick: held.append(s) or True))
    for _ in range(3):
        assert Simulator._while_planning(sim)  # type: ignore[arg-type]
    assert sim.doing == "planning (brake (plan 3, step 1 of 2))" and held == [LOOP.plan_budget_s] * 3


@pytest.mark.parametrize(("traffic", "speeds", "semantics"), [
    ("paper", "lane", "whole"), ("following", "lane", "whole"), ("following", "measured", "whole"),
    ("paper", "lane", "commit"), ("following", "measured", "commit")])
def test_spin_and_the_interpreter_drive_the_same_sound_drive(traffic: str, speeds: str, semantics: str,
                                                             tmp_path: Path) -> None:
    """The sound model's sensible plans are the same plans whichever engine finds them: a pinned drive planned by
    Spin is the interpreter's, summary (less its wall-clock figures and its configuration, which names the engine)
    and trace alike, with lane-wide speeds and with each tracked vehicle's own, deciding by whole plans and by
    committed parts with their escapes. One answer may be worded apart: where
    the interpreter proves there is no plan at any horizon, Spin answers only that there is none within it
    (``Engine.prove_beyond``); the AV does the same either way."""
    drives, plans = {}, []
    for engine in ("interpreter", "spin"):
        config = DriveConfig(1.0, engine=engine, model="sound", traffic=traffic, sensor="noisy",
                             tracking=speeds == "measured", vehicle_speeds=speeds,
                             semantics=semantics)
        summary = run_drive(3, config, str(tmp_path / engine)).to_json()
        plans.append(summary["plans"])
        text = json.dumps({k: v for k, v in summary.items() if k not in (*WALL_CLOCK, "config")}, sort_keys=True) \
            + (tmp_path / engine / "trace-seed3.jsonl").read_text()
        drives[engine] = text.replace("(no_plan)", "(no_plan_within_horizon)") if engine == "interpreter" else text
    assert drives["spin"] == drives["interpreter"]
    assert min(plans) > 10
