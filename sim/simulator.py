"""One closed-loop drive: the world (bodies, physics, traffic, sensors, faults), the observers, and the bookkeeping
against the truth, running the AV's driver.

Two clocks: decisions (one per action, 3 or 6 s) and physics (``LOOP.physics_dt_s``). What the AV decides is its
driver's, in the decision layer: the paper's rules (``sim.driver.paper.PaperDriver``: re-planning when a vehicle not
in the current plan is sensed, when the plan runs out, after ``replan_after_actions`` actions, and, with
``replan_on_violation``, on by default, not in the paper, as soon as a vehicle deviates from the prediction beyond
the tolerance, ``sim.tolerance.PlanCheck``) or the sound model (``sim.driver.sound.SoundDriver``: a decision is kept
only while its sets hold as the AV senses them; without a plan the AV keeps its lane safely, keeps what the last
decision proved, or hands over to the fallback). The simulator is their host (``sim.driver.host.Host``): what they
read, move and report through. Containment (``sim.containment``) is checked every control step under both models.
A decision is the control steps it yields (``sim.driver.control.Steps``); the world's loop (``_perform``) applies
each and ticks the world after it, so the world's clock never advances inside a decision (a missed-opportunity
replay steps a saved copy of the world and restores it). The world is re-centred on the AV every kilometre so
coordinates stay small however far it drives.

Every part (scene, car, traffic, sensors, planner, observers) is passed in (``sim.parts``);
the simulator owns its scene's ``BulletClient`` and one ``numpy`` generator seeded with the
drive's seed, which every random part draws from.
"""

from __future__ import annotations

import contextlib
import math
import time
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np

from sim import opportunity
from sim.containment import Containment
from sim.driver import control, plan
from sim.driver.control import Steps, lane_of, lane_y
from sim.driver.discretiser import discretise
from sim.driver.monitor import Breach, BreachKind, Sighting
from sim.driver.paper import PaperDriver
from sim.driver.readings import Reading
from sim.driver.sound import SoundDriver
from sim.executor import Executor
from sim.faults import GHOST_BODY, FaultEvent, FaultySensor, SteeringFault, attribute
from sim.observers import StepEvent, TraceWriter
from sim.parts import DriveConfig, Parts
from sim.safety import SafetyMonitor
from sim.sensors import RaySensor, SensorModel, in_range, oncoming_view_m
from sim.summary import Failure, RunSummary, Takeover
from sim.tolerance import PlanCheck, ToleranceReport, Violation
from sim.tracking import Detection, Track, Tracker
from sim.vehicle import KinematicCar, Pose, first_contact
from spec.actions import Action
from spec.answers import Answer
from spec.assumptions import PROFILES
from spec.dynamics import Overtaken
from spec.envelope import MINIMAL_RISK
from spec.errors import ScenarioError
from spec.faults import lost_control
from spec.files import scenario_to_dict
from spec.kinds import FailureKind
from spec.lanes import Lane
from spec.physical import CAR, LOOP, SENSORS
from spec.scenario import Scenario
from spec.sound import Sound
from spec.state import State

RECENTRE_M = 1000.0
START_UP_S = 4.0  # holding the lane from standstill at the start (and after a restart): reach the common speed
MIN_EPISODE_KM = 0.001  # a collision again before the AV has moved a metre since the last one ends the drive
#: A drive whose AV moves less than a car length for this long (simulated time) is blocked: the episode is given up
#: (``FailureKind.BLOCKED``) and starts again like one after a collision, or the drive ends. A bound on the
#: experiment, not on the model: four times the longest wait the fallback states (its return wait, 25.5 s), so no
#: stated stop (a stop event: at most 3 s of braking and 5 s standing) or wait reaches it. Without it a wreck the AV
#: cannot pass (wrecks stand until left behind) held a drive for ever.
BLOCKED_S = 4 * MINIMAL_RISK.return_wait_s
SNAPSHOT_EVERY = 10
SENSOR_STREAM = 1  # the second word of the sensor's seed: [seed, 1]
Report = Callable[[tuple[int, float]], None]


class Simulator:
    """A physics world, the AV, traffic, sensors and a planner, assembled from ``parts``, driven by one seeded
    generator; the host of the AV's driver (``sim.driver.host.Host``: what it reads, moves and reports)."""

    #: the sound model's driver, assembled afresh with the scene (at the start, and after a restart)
    driving: type[SoundDriver[Containment]] = SoundDriver

    def __init__(self, seed: int, parts: Parts, replan_on_violation: bool = True,
                 tolerance: ToleranceReport | None = None, report: Report | None = None, snapshots: int = 0,
                 restart_after_collision: bool = False, opportunity_checks: int = 0) -> None:
        self.snapshots = snapshots  # keep every SNAPSHOT_EVERY-th plan's scenario, up to this many
        self.report, self._next_report_km = report, 1.0  # (seed, km) after every kilometre
        self.replan_on_violation = replan_on_violation
        self.restart_after_collision = restart_after_collision
        self.opportunity_checks = opportunity_checks  # missed-opportunity replays per run, at most
        self.rng = np.random.default_rng(seed)
        # sensing and sampling draw from their own streams, so exact and noisy sensing meet the same traffic draws
        self.sensor_rng = np.random.default_rng([seed, SENSOR_STREAM])
        self.sample_rng = np.random.default_rng([seed, opportunity.STREAM])
        self.parts = parts
        self.planner, self.observers = parts.planner, parts.observers
        self.grid = parts.planner.grid
        self.sound = parts.planner.sound  # None: the paper model decides (and containment is only measured)
        # the sets containment is measured against (with the sound model's stated behaviour of vehicles overtaken)
        self.watch = None if parts.bounds is None else Sound(
            parts.bounds, overtaken=Overtaken.PHYSICS if self.sound is None else self.sound.overtaken)
        self.summary = RunSummary(seed, tolerance=tolerance or ToleranceReport())
        self.safety = SafetyMonitor()
        self.summary.safety = self.safety.report
        self.origin_km = 0.0
        self.faults = parts.faults
        self.faulty: FaultySensor | None = None  # the sensing faults' injectors, kept over restarts (their log too)
        self.steering = SteeringFault(parts.faults, seed)
        self.manoeuvre_faults: list[FaultEvent] = []  # sensing faults in the snapshots of the manoeuvre under way
        self.flagged = False  # the tracker flagged a contradiction at a decision of the manoeuvre under way
        self.steered: list[FaultEvent] = []  # steering faults under way during it
        self.sweep_every = max(1, round(1 / (SENSORS.sweep_hz * LOOP.physics_dt_s * LOOP.control_every_steps)))
        self._assemble()

    def _assemble(self) -> None:
        """A scene with the AV at the origin of its lane and traffic around it (at the start, and after a restart)."""
        self.scene = self.parts.scene()
        self.car = self.parts.car(self.scene, 0.0, lane_y(Lane.LEFT))
        self.traffic = self.parts.traffic(self.scene, self.rng, 0.0)
        self.sensor: SensorModel | FaultySensor = self.parts.sensor(self.scene, self.sensor_rng)
        if self.faults.sensing:
            if self.faulty is None:
                self.faulty = FaultySensor(self.sensor, self.faults, self.grid, self.summary.seed)
            self.faulty.inner, self.sensor = self.sensor, self.faulty
        self.executor = Executor(self.scene, self.car, Lane.LEFT, self.grid)
        self.safety.forget()
        self.plan_check: PlanCheck | None = None  # the paper model's plan under way, held against the truth
        self.doing = "start-up"  # what the AV was executing: recorded with every collision
        self._side = {car.body: car.x_m > 0 for car in self.traffic.left}
        self.visible = RaySensor(self.scene, self.sensor_rng)  # exact rays, no draws: is a vehicle sensed now?
        self._seen: set[int] = set()  # the bodies ``visible`` saw at ``_seen_at`` (the drive's clock)
        self._seen_at = -1.0
        self.containment: Containment | None = None  # the sets of the decision under way
        self.sighted: Sighting | None = None  # the vehicles the plan under way was made knowing (``sensed_anew``)
        self.broken_before = False  # a vehicle broke the previous decision's assumptions (the truth: bookkeeping)
        self.previous: Containment | None = None  # the sets of the decision before the one under way
        self.takeover: Takeover | None = None  # the fallback's take-over under way
        self.sweep: tuple[Reading, ...] | None = ()  # the last sweep the sensors delivered (None: it was dropped)
        self.swept_at = (0.0, 0.0)  # where the AV was when it was taken, along the road from the start (m), and when
        # with tracking, the planner sees the tracker's vehicles (``sim.tracking``); bodies only for bookkeeping
        self.tracker = (Tracker(self.parts.bounds, speed_error_mps=self.parts.speed_error_mps)
                        if self.parts.tracking and self.parts.bounds is not None else None)
        self.track_body: dict[int, int] = {}  # track -> the body of the reading last assigned to it (bookkeeping)
        #: when a list (set by a measurement, ``ci.bench.speeds``): every sweep's confirmed tracks read this sweep, each
        #: as (seconds since first read, its speed interval, its vehicle's true speed along its direction of travel)
        self.speed_log: list[tuple[float, tuple[float, float], float]] | None = None
        self.unresolved: frozenset[Lane] = frozenset()  # lanes where the tracker holds a contradiction
        self.controls = 0  # control steps since the scene was assembled: the sensors sweep on every ``sweep_every``-th
        #: the sound model's driver (None: the paper's rules decide) and the driver that decides (``_one_plan``)
        self.sound_driver = None if self.sound is None else self.driving(
            self, self.planner, self.grid, None if self.watch is None else self.watch.bounds)
        self.driver: SoundDriver[Containment] | PaperDriver = self.sound_driver or PaperDriver(
            self, self.planner, self.grid, self.replan_on_violation)
        self._on_sweep()

    # -- the physics clock ------------------------------------------------------------------
    def _tick(self, dt_s: float) -> bool:
        """After each control step: move traffic, look for contacts, count overtakes, re-centre."""
        self.summary.sim_time_s += dt_s
        pose = self.car.pose()
        self.traffic.advance(dt_s, pose)
        x = pose.x_m
        if self.containment is not None:
            self._contain(pose, dt_s)
        self.safety.observe(pose, lane_of(pose.y_m), self.traffic.left, self.traffic.oncoming,
                            self.summary.km, self.summary.sim_time_s, self.doing, self._implied_gap, self._attribution)
        lost = lost_control(pose.y_m, pose.yaw_rad)
        if lost is not None:
            self.fail(FailureKind.LOSS_OF_CONTROL, lost, f"during {self.doing}" + (
                f", steering offset {math.degrees(self.executor.steer_offset_rad):+.0f} degrees"
                if self.executor.steer_offset_rad else ""))
            return False
        car = first_contact(self.scene, self.car.body, self.traffic.cars())
        if car is not None:
            in_left = car in self.traffic.left
            self.safety.contact(car, Lane.LEFT if in_left else Lane.RIGHT, pose, self.summary.km,
                                self.summary.sim_time_s, self.doing, self._implied_gap(car.body),
                                self._attribution(car.body))
            lane = "left-lane" if in_left else "oncoming"
            self.fail(FailureKind.COLLISION, f"collision with a{'n' if lane == 'oncoming' else ''} {lane} vehicle",
                       f"{car.x_m - x:+.1f} m ahead, during {self.doing}", car.body)
            if self.takeover is not None:
                self.takeover.outcome = "collision"
            return False
        for car in self.traffic.left:
            ahead = car.x_m > x
            if self._side.get(car.body) and not ahead:
                self.summary.overtakes += 1
            self._side[car.body] = ahead
        if self.traffic.respawn_behind(x):
            self._side.update({car.body: car.x_m > x for car in self.traffic.left})
        if x > RECENTRE_M:
            self._recentre(x)
            x = 0.0  # the car is now at the origin
        self.summary.km = self.origin_km + x / 1000
        self.controls += 1
        if self.swept():
            self._on_sweep()
        if self.report and self.summary.km >= self._next_report_km:
            self.report((self.summary.seed, self.summary.km))
            self._next_report_km = int(self.summary.km) + 1
        return True

    def _recentre(self, x_m: float) -> None:
        """Move the world back by ``x_m`` (the car's place): the bodies, the references, and every decision's sets
        the loop may still read, each once (the decision under way's, the one before it, the last proof the driver
        keeps, the paper's sighting), and the driver's proved reference."""
        self.origin_km += x_m / 1000
        self.car.shift_x(-x_m)
        self.traffic.shift_x(-x_m)
        self.executor.x_ref_m -= x_m
        held: list[Containment | Sighting | None] = [self.containment, self.previous, self.sighted]
        if self.sound_driver is not None:
            held.append(self.sound_driver.proved)
            self.sound_driver.shift_x(-x_m)
        for sets in {id(s): s for s in held if s is not None}.values():
            sets.shift_x(-x_m)
        if self.tracker is not None:
            self.tracker.shift_x(-x_m)

    # -- containment (``sim.containment``) --------------------------------------------------------------------
    def view_m(self, readings: tuple[Reading, ...], av_y_m: float) -> float | None:
        """How far the sound model's snapshot sees the oncoming lane (``sim.sensors.oncoming_view_m``, the sensing
        error its bounds allow): where a left-lane vehicle hides it, the oncoming phantom stands."""
        assert self.sound is not None
        return oncoming_view_m(readings, av_y_m, self.sound.bounds.sensing_error_m)

    def contain_from(self, readings: tuple[Reading, ...], pose_x_m: float, lane: Lane, view_m: float | None = None,
                     sensed_sets: bool = False, read: tuple[Reading, ...] | None = None) -> None:
        """Containment from this snapshot on, against the drive's bounds and the snapshot's view of the oncoming lane
        (a snapshot that makes no scenario: none); with ``sensed_sets`` the readings are sets that hold the sensing
        error (``spec.sound.Sound.sensed_sets``), as the decision's planner read them, narrowed from what was
        ``read``."""
        old = self.containment
        self.previous = old
        self.broken_before = old is not None and old.world_breached()
        if old is not None and not old.ended:
            old.ended = True
            self.summary.unseen_breaches += int(self.sound is not None and old.unseen())
        self.containment = None
        if self.watch is None:
            return
        try:  # the sets a sound plan is proved against: where each vehicle was sensed, not its whole cell; a snapshot
            if self.sound is None:  # the paper model's rules cannot read (two vehicles in one cell) makes none
                discretise(readings, lane, self.grid)
            scenario = discretise(readings, lane, self.grid, measured=True)
        except ScenarioError:
            return
        self.summary.decisions += 1
        watch = replace(self.watch, oncoming_view_m=view_m, sensed_sets=sensed_sets)
        self.containment = Containment(self.summary.decisions, watch, scenario, readings, self.grid, pose_x_m,
                                       self.summary.sim_time_s, self.traffic.cars(), read)

    def _contain(self, pose: Pose, dt_s: float) -> None:
        """One control step's containment check against the truth (the simulator's bookkeeping); under the sound
        model a breach of the AV's own envelope (its odometry against its reference) ends the decision under way, a
        vehicle's only once the AV senses it (``SoundDriver.on_sweep``)."""
        c, report = self.containment, self.summary.containment
        assert c is not None
        report.checked_s += dt_s
        if c.world_breached():
            report.breached_s += dt_s
        t, km = self.summary.sim_time_s, self.summary.km
        found = c.check(t, km, pose, self.traffic.left, self.traffic.oncoming, self.doing, self._sensed)
        if self.sound_driver is not None and self.sound_driver.enveloped:
            av = c.check_av(t, km, pose, self.executor.x_ref_m, self.executor.v_ref_mps, self.executor.lane_due,
                            self.doing)
            found += [av] if av is not None else []
        for breach in found:
            report.add(breach)
        d = self.sound_driver
        if any(b.kind is BreachKind.AV_ENVELOPE for b in found) and d is not None and self.takeover is None:
            d.interrupt = True

    def _sensed(self, car: KinematicCar) -> bool:
        """Whether ``car`` is sensed now (exact rays, whatever the drive's sensor model: a vehicle the sensors could
        report, so a decision could know it); the rays are cast once per control step, when first asked."""
        if self._seen_at != self.summary.sim_time_s:
            pose = self.car.pose()
            truth = in_range(pose.x_m, pose.y_m, self.traffic.left, self.traffic.oncoming)
            self._seen, self._seen_at = {r.body for r in self.visible.read(truth)}, self.summary.sim_time_s
        return car.body in self._seen

    def _attribution(self, body: int) -> str | None:
        """Whether an encounter with ``body`` happened inside the assumptions (no breach by it under the decision
        under way, or while a decision plans under the one before it; the AV's own envelope breach counts as inside)
        or after one broke (by it, or an injected steering fault under way); None without bounds.

        The envelope is what the proofs assume of the AV's own motion. Its executor leaving it is the AV's own error,
        part of what the proofs speak for, so an encounter then counts as inside; an injected steering fault is the
        world's, as a sensing fault is, and an encounter while one turns the AV's steering is after it broke."""
        steering = self.steering.active
        if steering is not None and self.watch is not None:
            return (f"after an assumption broke: steering fault ({math.degrees(steering.offset_rad):+.0f} degrees) "
                    f"under way")
        if self.takeover is not None:
            return (f"{'after an assumption broke' if self.takeover.after_breach else 'inside the assumptions'}: "
                    f"fallback since {self.takeover.t_s:.1f} s ({self.takeover.cause})")
        c = self.containment
        if self.doing.startswith("planning (") and self.previous is not None:
            c = self.previous  # while a decision plans, the AV still does what the one before decided, under its sets
        if c is None:
            return None if self.watch is None else "after an assumption broke: no scenario from the snapshot"
        breach = c.breached.get(body)
        if breach is None and (hidden := self._hidden(c, body)) is not None:
            return f"after an assumption broke: {hidden.kind.value} by {hidden.size}, {hidden.vehicle}"
        if breach is None or breach.kind.inside:
            return "inside the assumptions"
        return (f"after an assumption broke: {breach.kind.value} by {breach.size}, "
                f"{self.summary.sim_time_s - breach.t_s:.1f} s before")

    def _hidden(self, c: Containment, body: int) -> Breach | None:
        """``Containment.hidden`` of the vehicle ``body``: unknown to the decision, unseen (one touching the AV, where
        no ray reaches), where no phantom could be."""
        for lane, cars in ((Lane.LEFT, self.traffic.left), (Lane.RIGHT, self.traffic.oncoming)):
            for car in cars:
                if car.body == body:
                    return c.hidden(self.summary.sim_time_s, self.summary.km, self.car.pose(), lane, car, self.doing)
        return None

    def _event(self, kind: FailureKind, cause: str, detail: str) -> Failure:
        """A failure record stamped with where and when the drive is now."""
        return Failure(kind, cause, detail, round(self.summary.km, 3), round(self.summary.sim_time_s, 1))

    def fail(self, kind: FailureKind, cause: str, detail: str, body: int | None = None) -> None:
        in_snapshot = self.faulty.in_sweep() if self.faulty else []
        fault = attribute(body, self.manoeuvre_faults if kind.ends_run else in_snapshot,
                          self.steered if kind.ends_run else [])
        self.summary.failures.append(replace(self._event(kind, cause, detail),
                                             fault=None if fault is None else fault.kind.value,
                                             flagged=self.flagged if self.tracker is not None else None))

    def decided(self, lane: Lane) -> None:
        """A decision was taken from the last sweep: a decision in the left lane starts a new manoeuvre; the faults
        that changed its snapshot are remembered for the attribution (``sim.faults.attribute``)."""
        if lane is Lane.LEFT:
            self.manoeuvre_faults = []
            self.steered = [] if self.steering.active is None else [self.steering.active]
            self.flagged = False
        self._remember_faults()

    def _remember_faults(self) -> None:
        """The sensing faults that changed the last sweep join the manoeuvre's, with whether the tracker flagged it."""
        self.flagged = self.flagged or bool(self.unresolved)
        for event in self.faulty.in_sweep() if self.faulty else ():
            if event not in self.manoeuvre_faults:
                self.manoeuvre_faults.append(event)

    # -- the decision clock ------------------------------------------------------------------
    def drive(self, km: float, until_failure: bool = False, sensing_only: bool = False) -> RunSummary:
        """Drive ``km`` kilometres (or until the first failure, with ``sensing_only`` the first a sensing fault
        caused); at a collision stop, or with ``restart_after_collision`` start again where the drive stands
        (``_restart``)."""
        started = time.perf_counter()
        ok = self._perform(self.executor.holding(START_UP_S, self.grid.speed))  # start-up: reach the common speed
        episode_km = 0.0
        moved = (self.summary.km, self.summary.sim_time_s)  # where and when the AV last moved a car length
        while self.summary.km < km and not (until_failure and self.summary.ended(sensing_only)):
            if not ok:
                if not self.restart_after_collision or self.summary.km - episode_km < MIN_EPISODE_KM:
                    break  # a collision ends the drive; so does one that comes again before the AV has moved
                episode_km = self.summary.km
                ok = self._restart()
                moved = (self.summary.km, self.summary.sim_time_s)
                continue
            ok = self.decide_once()
            if (self.summary.km - moved[0]) * 1000 >= CAR.length_m:
                moved = (self.summary.km, self.summary.sim_time_s)
            elif ok and self.summary.sim_time_s - moved[1] > BLOCKED_S:
                self.fail(FailureKind.BLOCKED, "blocked", f"the AV moved less than a car length in "
                           f"{self.summary.sim_time_s - moved[1]:.0f} s, during {self.doing}")
                if not self.restart_after_collision:
                    break
                episode_km = self.summary.km
                ok = self._restart(collision=False)
                moved = (self.summary.km, self.summary.sim_time_s)
        self.summary.wall_s = time.perf_counter() - started
        self.summary.traffic_collisions += self.traffic.collisions
        injectors = [*(self.faulty.injectors.values() if self.faulty else ()), *filter(None, [self.steering.injector])]
        self.summary.faults = {i.fault.kind.value: {"offered": i.offered, "started": i.started,
                                                   "sweeps": sum(e.sweeps for e in i.events)} for i in injectors}
        return self.summary

    def decide_once(self) -> bool:
        """One decision, its control steps applied to the world one at a time, each followed by the world's tick;
        False on a collision (or a loss of control)."""
        return self._perform(self._one_plan())

    def _perform(self, steps: Steps) -> bool:
        """The world's loop: what the AV does (``steps``), one control step at a time, the executor moving the car
        through the physics, then the world's tick (traffic, contacts, containment, sensors: ``_tick``); the steps
        hear whether the world went on. False on a collision (or a loss of control)."""
        return self.executor.perform(steps, self._tick)

    def _restart(self, collision: bool = True) -> bool:
        """After a collision (or a blocked episode, not counted among ``restarts``): a fresh scene, AV and traffic
        (drawn from the drive's generator as it stands); the distance, the failures and every report go on, so an
        audit measures collisions per km over long runs (as the paper's simulation counted kilometres between
        failures)."""
        self.summary.restarts += int(collision)
        self.summary.traffic_collisions += self.traffic.collisions
        self.origin_km = self.summary.km
        self.steering.end()
        self.scene.close()
        self._assemble()
        self.doing = "start-up after a collision" if collision else "start-up after a blocked episode"
        return self._perform(self.executor.holding(START_UP_S, self.grid.speed))

    # -- the sensors' clock (``spec.physical.SENSORS.sweep_hz``) ------------------------------------------------
    def swept(self) -> bool:
        """Whether the sensors swept at the end of this control step: a decision is made only then, so its
        snapshot is never older than the car's pose."""
        return self.controls % self.sweep_every == 0

    def _log_speeds(self, tracks: tuple[Track, ...]) -> None:
        """Each track read this sweep beside its vehicle's true speed (the measurement's only look at the truth)."""
        speeds = {car.body: abs(car.velocity_mps) for car in (*self.traffic.left, *self.traffic.oncoming)}
        assert self.speed_log is not None
        self.speed_log += [(self.summary.sim_time_s - t.since_s, t.speed_mps, speeds[self.track_body[t.id]])
                           for t in tracks if t.read_m is not None and self.track_body.get(t.id) in speeds]

    def _told_speed(self, lane: Lane, speed_mps: tuple[float, float]) -> tuple[float, float] | None:
        """A track's speed interval as the planner is told it (``Parts.measured_speeds``; None: not told): one never
        read is anything from a standstill to its lane's top, the bounds' (``spec.dynamics``: it may stand)."""
        if not self.parts.measured_speeds or self.parts.bounds is None:
            return None
        low, high = speed_mps
        return (low, self.parts.bounds.speeds(lane).high_mps) if math.isinf(high) else (low, high)

    def _on_sweep(self) -> None:
        """A sweep: the sensors read the truth (through any fault injectors), and the steering fault moves on."""
        pose = self.car.pose()
        self.summary.sweeps += 1
        self.swept_at = (self.origin_km * 1000 + pose.x_m, self.summary.sim_time_s)
        raw = self.sensor.read(in_range(pose.x_m, pose.y_m, self.traffic.left, self.traffic.oncoming,
                                        av_speed_mps=pose.along_mps))
        if self.tracker is None:
            self.sweep = raw
        else:
            view = self.tracker.update(self.summary.sim_time_s, pose.x_m, pose.along_mps,
                                       None if raw is None else [Detection(r.lane, r.dx_m, r.rate_mps) for r in raw],
                                       pose.y_m)
            for track in (*view.planned, *view.held):
                if raw is not None and track.detection is not None:
                    self.track_body[track.id] = raw[track.detection].body
            # a kept track (no reading this sweep) goes to the planner with its interval: its bounds since last seen;
            # the sound model plans around held appearances too (what the tracker cannot resolve is uncertainty to it,
            # never hidden), the paper's rules do not (an appearance held is how a fake gap stays closed for them)
            told = (*view.planned, *view.held) if self.sound is not None else view.planned
            self.sweep = tuple(Reading(t.lane, self.track_body.get(t.id, GHOST_BODY), t.place_m - pose.x_m,
                                       (0.0, 0.0) if t.read_m is not None else (t.place_m - t.lo_m, t.hi_m - t.place_m),
                                       speed_mps=self._told_speed(t.lane, t.speed_mps))
                               for t in told)
            self.unresolved = view.unresolved
            if self.speed_log is not None:
                self._log_speeds(view.planned)
        if self.sound_driver is not None:
            self.sound_driver.on_sweep(self.origin_km * 1000 + pose.x_m)  # the AV's own monitor, the fallback's view
        if self.takeover is not None:
            self._remember_faults()  # the fallback acts on every sweep, not only on a decision's
        self.executor.steer_offset_rad = self.steering.on_sweep()
        if self.steering.active is not None and self.steering.active not in self.steered:
            self.steered.append(self.steering.active)

    def refused(self, actions: tuple[Action, ...], under_way: tuple[Action, ...]) -> bool:
        """Whether the tracker's contradiction refuses the overtake ``actions`` would start (``plan.refuses``; only
        with tracking); a refusal is counted (the decision drops the rest of the plan ``under_way``)."""
        if self.tracker is None:
            return False
        pose = self.car.pose()
        if not plan.refuses(bool(self.unresolved), actions, under_way, lane_of(pose.y_m), pose.along_mps,
                            self.grid.speed):
            return False
        self.summary.refusals += 1
        return True

    def sight(self, readings: tuple[Reading, ...], av_x_m: float, t_s: float | None = None) -> None:
        """The vehicles a plan is made knowing, for the paper's re-planning rule (``Sighting``), under the drive's
        bounds (without any: the paper's world, every vehicle at the common speed, sensed exactly): ``readings`` taken
        with the AV at ``av_x_m`` at ``t_s`` (default: now)."""
        bounds = self.watch.bounds if self.watch is not None else PROFILES["paper"]
        self.sighted = Sighting(readings, bounds, av_x_m, self.summary.sim_time_s if t_s is None else t_s)

    def sensed_anew(self) -> bool:
        """Whether the last sweep shows a vehicle the plan under way was not made knowing: re-plan (the paper's rule;
        readings carry no identity, so "new" is a reading no vehicle of the plan's snapshot can explain). Its readings
        are placed from where the AV was when it was taken, at that time: an action may end after the sweep (a
        decision acts a control step after its snapshot, and actions on 5.25 m cells are not whole sweeps)."""
        assert self.sighted is not None
        return self.sighted.new(self.sweep or (), *self.where_swept())

    def where_swept(self) -> tuple[float, float]:
        """Where the AV was when the last sweep was taken (in the road's frame now) and when."""
        along_m, t_s = self.swept_at
        return along_m - self.origin_km * 1000, t_s

    def _one_plan(self) -> Steps:
        """One decision, from the sensors' next sweep: the driver's control steps."""
        y_ref = lane_y(lane_of(self.car.pose().y_m))
        if not (yield from control.until_sweep(self.swept, self.executor.v_ref_mps, y_ref)):
            return False
        return (yield from self.driver.decision())

    def predicting(self, plan_id: int, seen: tuple[Reading, ...], states: tuple[State, ...]) -> PlanCheck:
        """The paper model's plan ``plan_id`` (made on ``seen``, predicting ``states``) held against the truth as it
        executes (``tolerance.PlanCheck``), its gaps implied while an action is under way read by the safety
        measures."""
        def observe(step: int, action: Action, state: State, violations: list[Violation]) -> None:
            self._observe(plan_id, step, action, state, violations)

        self.plan_check = PlanCheck(self.summary.tolerance, plan_id, seen, states, self.grid, self.traffic.cars,
                                    lambda: self.car.pose().x_m, observe)
        return self.plan_check

    def _implied_gap(self, body: int) -> float | None:
        """The gap to ``body`` the paper model's action under way implies at its end (None: none followed)."""
        return None if self.plan_check is None else self.plan_check.implied.get(body)

    def planned(self, answer: Answer, scenario: Scenario, lane: Lane) -> None:
        """Count a plan, its latency and (in the AV's lane) its missed opportunity; keep every SNAPSHOT_EVERY-th
        scenario."""
        self.summary.plans += 1
        self.summary.plan_ms.append(answer.elapsed_ms)
        if lane is Lane.LEFT:
            self._opportunity(answer, scenario)
        if len(self.summary.snapshots) < self.snapshots and self.summary.plans % SNAPSHOT_EVERY == 1:
            self.summary.snapshots.append(scenario_to_dict(scenario))

    def pose(self) -> Pose:
        """The car's pose as its odometry gives it."""
        return self.car.pose()

    def check_snapshot(self) -> None:
        """The containment check at a decision's snapshot itself (sensed farther off than the error bound, or
        unknown)."""
        if self.containment is not None:
            self._contain(self.car.pose(), 0.0)

    def resume(self, monitor: Containment) -> None:
        """The decision under way goes on under an earlier decision's sets (``SoundDriver.keep_proved``)."""
        self.containment = monitor

    def kept(self, kind: FailureKind, cause: str, detail: str) -> None:
        """A decision without a plan kept the one under way (``kept_plans``)."""
        self.summary.kept_plans.append(self._event(kind, cause, detail))

    def traced(self, step: int, action: Action | None, since_s: float) -> None:
        """``_observe`` a sound decision's action (None: a minimal-risk manoeuvre or a take-over) since ``since_s``."""
        self._observe(self.summary.plans, step, action, None, [], since_s)

    def take_over(self, cause: str, lane: Lane) -> None:
        """Record the fallback's take-over from ``lane`` (``SoundDriver.fallback``): whether an assumption had broken
        (under the decision before, the one under way, or the take-over it follows), and what it ended."""
        again = self.takeover is not None and self.takeover.outcome == "under way"
        broke = self.broken_before or (self.containment is not None and self.containment.world_breached()) \
            or (again and self.takeover is not None and self.takeover.after_breach)  # one take-over after another
        if again and self.takeover is not None:
            self.takeover.outcome = "taken over again"
        self.takeover = Takeover(round(self.summary.km, 3), round(self.summary.sim_time_s, 1), cause, lane.value,
                                 broke)
        self.summary.takeovers.append(self.takeover)

    def taking_over(self) -> bool:
        """Whether the fallback's take-over is under way."""
        return self.takeover is not None

    def hand_back(self) -> None:
        """A decision found a plan or a safe step: the take-over under way (if any) ends here."""
        if self.takeover is not None:
            if self.takeover.outcome == "under way":
                self.takeover.outcome = "handed back"
            self.takeover = None

    def _opportunity(self, answer: Answer, scenario: Scenario) -> None:
        """A decision in the AV's own lane: when the planner does not start an overtake with a target in sight, count
        it, and on a sample of such decisions replay the canonical overtakes (``sim.opportunity``); the world is
        left exactly as it was."""
        x = self.car.pose().x_m
        target = opportunity.target_ahead(x, self.traffic.left)
        refusal = None if target is None else opportunity.refusal(answer)
        if target is None or refusal is None:
            return
        report = self.summary.opportunities
        report.count(refusal, "qualifying")
        if report.total("checked") >= self.opportunity_checks or self.sample_rng.random() >= opportunity.SAMPLE:
            return
        report.count(refusal, "checked")
        gap_m = target.x_m - x - CAR.length_m
        outcome, accelerates = opportunity.Replay(self.scene, self.car, self.traffic, self.grid).first_success(target)
        report.count(refusal, outcome.value)
        if outcome is opportunity.Outcome.MISSED and len(report.missed) < opportunity.MAX_RECORDS:
            said = " ".join(a.value for a in answer.actions[:4]) or answer.status.value
            report.missed.append(opportunity.Opportunity(round(self.summary.km, 3), round(self.summary.sim_time_s, 1),
                                                         refusal.value, said, accelerates, gap_m,
                                                         scenario_to_dict(scenario)))

    def _observe(self, plan_id: int, step: int, action: Action | None, predicted: State | None,
                 violations: list[Violation], since_s: float | None = None) -> None:
        """Tell the observers an action (None: a fallback's or minimal-risk manoeuvre's control) ended now; without
        cells predicted (the sound model), what the AV was doing since ``since_s`` is told as well."""
        if not self.observers:
            return
        pose = self.car.pose()
        measured = {lane: [c.x_m - pose.x_m for c in cars]
                    for lane, cars in (("left_lane", self.traffic.left), ("right_lane", self.traffic.oncoming))}
        t_s = self.summary.sim_time_s
        event = StepEvent(t_s, self.summary.km, plan_id, step, action, pose.x_m, pose.y_m, pose.along_mps, measured,
                          predicted, tuple(violations), self.doing, 0.0 if since_s is None else t_s - since_s)
        for observer in self.observers:
            observer.on_step(event)

    def close(self) -> None:
        self.scene.close()


def run_drive(seed: int, config: DriveConfig, out_dir: str | None = None, report: Report | None = None) -> RunSummary:
    """One drive in a fresh simulator assembled as ``config`` says (the unit a worker process runs); with
    ``out_dir``, its trace goes to ``trace-seedS.jsonl`` there; ``report`` hears (seed, km) every km."""
    with contextlib.ExitStack() as stack:
        observers: tuple[TraceWriter, ...] = ()
        if out_dir:
            Path(out_dir).mkdir(parents=True, exist_ok=True)
            observers = (TraceWriter(stack.enter_context((Path(out_dir) / f"trace-seed{seed}.jsonl").open("w"))),)
        sim = assemble(seed, config, observers, report)
        stack.callback(sim.close)
        return sim.drive(config.km, config.stops_at_failure, config.until_sensing_failure)


def assemble(seed: int, config: DriveConfig, observers: tuple[TraceWriter, ...] = (),
             report: Report | None = None, simulator: type[Simulator] | None = None) -> Simulator:
    """The simulator of the drive of ``seed`` under ``config`` (what ``run_drive`` drives, and a replay redrives);
    ``simulator``: a subclass that observes more (a benchmark's)."""
    tolerance = ToleranceReport(config.step_tolerance_cells, config.plan_tolerance_cells)
    return (simulator or Simulator)(seed, config.parts(observers), config.replan_on_violation, tolerance, report,
                                    config.snapshots, config.restart_after_collision or config.until_sensing_failure,
                                    config.opportunity_checks)
