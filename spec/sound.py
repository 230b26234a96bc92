"""The sound model's rules, each written once: what the AV may do so that the safety specification holds for every
motion inside the stated assumptions, at every instant, not only at ticks.

Sets, not cells. Every vehicle is an interval of positions at the plan's start (its cell's extent,
``spec.cells``, widened by the sensing error unless the snapshot's extents hold it, and by the snapshot's age;
a phantom where each sensor's view ends, ``spec.assumptions``)
that grows with its lane's speed interval: a same-direction vehicle is within ``[lo + v_low t,
hi + v_high t]``, an oncoming one within ``[lo - v_high t, hi - v_low t]``. The AV is its reference
(``spec.envelope``) plus the tracking error. A step is safe when, over its whole window (from the
start of the ramp into it to its end), every vehicle in conflict keeps the gap of
``spec.safety.SAFETY`` at the worst closing speed its bounds and the AV's envelope allow:

- ``AHEAD``: a same-direction vehicle that may be ahead of the AV, while the AV occupies the left
  lane: ``lo + v_low t - (x + e_x) - L >= max(g_min, tau (v + e_v - v_low))``;
- ``ONCOMING``: an oncoming vehicle not yet certainly past the AV, while any part of the AV is in
  the right lane: ``lo - v_high t - (x + e_x) - L >= max(g_min, tau (v + e_v + v_high))``;
- ``CUT_IN``: while the AV moves sideways into the left lane, each same-direction vehicle must be
  certainly ahead as above, or certainly behind with ``(x - e_x) - (hi + v_high t) - L >=
  max(g_min, tau (v_high - v + e_v))``.

- ``BEHIND``: where followers keep their speed whatever the AV does (``Bounds.followers_react``
  False, the paper's traffic), each follower while the AV's reference is slower than ``v_high``
  (``rear_binds``), with the cut-in's gap.

A same-direction vehicle behind the AV in its own lane follows it (a lane keeps its order); where
followers react, a rear-end collision is the follower's to avoid and it is no conflict. The state
remembers which ones follow (``SoundState.followers``), since an interval behind a braking AV grows
past it. Each condition
is a threshold on the vehicle's start interval, the extreme over the window of a function of the
reference alone; the reference is piecewise quadratic, so the extreme is exact (the ends of each
piece and a vertex inside it). Goal fields hold only for every position; a plan's last state must admit the
minimal-risk manoeuvre for ever (``continuation_violation``). Phantoms are in every safety
condition and in no goal field (a goal speaks of the vehicles sensed).
"""

from __future__ import annotations

import enum
import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, NamedTuple

from spec.actions import ACTION_RULES, Action
from spec.assumptions import DEFAULT_PROFILE, Bounds, Phantom, check_bounds, parse_speeds, profile
from spec.cells import left_extent_m, oncoming_extent_m
from spec.dynamics import Dynamics, Overtaken, parse_overtaken, passing_windows_s
from spec.envelope import CLOSING_EPS_MPS, MINIMAL_RISK, TRACKING, MinimalRisk, Piece, Reference, Tracking
from spec.errors import OptionError, check_number
from spec.escapes import COMMIT, Commitment, Semantics, parse_escape_kinds, parse_most_actions, parse_semantics
from spec.grid import COMMON_SPEED_MPS, Grid
from spec.lanes import Lane
from spec.models import GoalRule
from spec.motion import Ramp, action_speed_mps, ramp_gain_m, ramp_s
from spec.physical import SENSORS
from spec.safety import SAFETY, Conflict, SafetySpec
from spec.tracking import VEHICLE_SPEED_CHANGE, Speed, SpeedChange

if TYPE_CHECKING:
    from spec.scenario import Scenario

#: Conditions are held to this much slack on the safe side, so that float rounding never makes a gap look large.
EPS_M = 1e-9
#: The most step answers one scenario's rules remember (a few MB; a longer walk starts again).
MEMO_ENTRIES = 50_000


class Checks(enum.Enum):
    """What a step of the sound model's code path is checked against."""

    PHYSICAL = "physical"  # the safety specification over every motion within the bounds (the sound model)
    PAPER_CELLS = "paper cells"  # the paper's cell rules on the nominal cells: the identity check, zero bounds only


@dataclass(frozen=True, slots=True)
class Sound:
    """The sound model's parameters: the assumptions of the world, the specification, the AV's envelope."""

    bounds: Bounds
    safety: SafetySpec = SAFETY
    tracking: Tracking = TRACKING
    start_mps: float | None = None  # the AV's measured speed at the snapshot; None: the common speed
    minimal_risk: MinimalRisk = MINIMAL_RISK
    checks: Checks = Checks.PHYSICAL
    #: how far ahead the front-right sensor saw the oncoming lane at the snapshot, metres (None: its whole range): a
    #: left-lane vehicle hides the lane from there on, and the oncoming phantom stands there (``phantoms``)
    oncoming_view_m: float | None = None
    #: how an answer is formed (``spec.escapes``): committed actions with a proved escape and a predicted
    #: continuation; None: whole plans, each proved to its end and for ever after
    commitment: Commitment | None = None
    #: how fast a vehicle whose speed was measured can change it (``spec.dynamics``): the scenario's ``left_mps`` and
    #: ``right_mps`` give each one's speed interval at the snapshot; a vehicle without one keeps its lane's speeds
    speed_change: SpeedChange = VEHICLE_SPEED_CHANGE
    #: what a measured same-direction vehicle may do while the AV is in the passing lane (``spec.dynamics``): speed
    #: up as physics allows, or, as a stated profile, not at all
    overtaken: Overtaken = Overtaken.PHYSICS
    #: a sideways move under way at the snapshot, into the scenario's lane: the most time it may still keep the AV in
    #: both lanes, s (0: none; at most ``Tracking.lateral_s``). Until then the AV is in both lanes, entering the left
    #: one when that is the scenario's lane (``SoundRules.window``): what a decision taken during a move proves
    #: finishing the move (the lane it goes to) or undoing it (the lane it left) against
    sideways_s: float = 0.0
    #: how far ahead of the AV's reference, where the plan starts, the car and its sensors stood at the snapshot, m
    #: (negative: behind it; at most the envelope's position error either way). A plan made from the proved reference
    #: the car runs on (``sim.driver.decide.plan_start``) reads its vehicles from there, and every phantom, at an edge
    #: of what the sensors saw, stands that much farther ahead of the reference. 0: the plan starts at the car
    sensors_ahead_m: float = 0.0
    #: whether the scenario's sensed extents (``Scenario.left_m``, ``right_m``) are sets each vehicle is known to be in
    #: at the snapshot, the sensing error held: readings narrowed by the sets of the last proof, which still holds
    #: (``sim.driver.monitor.Monitor.refine``). False: readings, each vehicle within the sensing error of its own
    sensed_sets: bool = False
    #: whether the plan's AV is the proved reference the car runs on (``sim.driver.decide.plan_start``), whose place
    #: advances at exactly its speed, the plan's start speed, while the snapshot ages (``aging_mps``); False: the car,
    #: its reference restarted there when the plan acts
    from_reference: bool = False

    def phantoms(self) -> tuple[Phantom, ...]:
        """The phantoms of this snapshot: the bounds' own, the oncoming one where the view of that lane ended; each
        moved by ``sensors_ahead_m`` (their edges are the sensors', the plan's AV is the reference) and nearer by its
        lane's ``age_m`` (a vehicle beyond the view at the snapshot may have come that much closer by the plan's
        start), never past the AV (an oncoming vehicle that has passed it is behind it, out of the plan's way)."""
        ahead = self.sensors_ahead_m
        found = self.bounds.phantom_vehicles(self.oncoming_view_m)
        if not self.bounds.latency_s and ahead == 0:
            return found
        out = []
        for p in found:
            age = self.age_m(p.lane)
            why = "".join(((f", the sensors {ahead:g} m ahead of the reference" if ahead else ""),
                           (f", aged {age:g} m" if age else "")))
            out.append(replace(p, dx_m=math.copysign(max(abs(p.dx_m) + (ahead if p.dx_m > 0 else -ahead) - age,
                                                          PHANTOM_NEAREST_M), p.dx_m), why=f"{p.why}{why}"))
        return tuple(out)

    @property
    def aging_mps(self) -> tuple[float, float]:
        """The AV's speeds while the snapshot ages: the loop holds its reference speed meanwhile. A plan from that
        reference (``from_reference``) has it for its AV, and its start speed (``start_mps``) is the reference's: the
        plan's AV drives at exactly that speed (``sim.executor.Executor.control`` advances the reference's place by
        its speed). A plan from the car has the car, within the envelope's speed error (``Tracking.speed_mps``) of
        the reference, and its start speed (``start_mps``; None: the common speed) is the car's, within that error of
        the same reference: so the plan's AV drives within twice that error of its start speed, never below a
        standstill."""
        # None: the common speed, every grid's (``spec.grid.Grid.speed_mps``; no grid is built with another)
        start = float(COMMON_SPEED_MPS) if self.start_mps is None else self.start_mps
        slack = 0.0 if self.from_reference else 2 * self.tracking.speed_mps
        return max(0.0, start - slack), start + slack

    def closing_mps(self, lane: Lane, highest_mps: float | None = None) -> float:
        """The fastest a vehicle of ``lane`` moves against the AV while the snapshot ages (the AV at ``aging_mps``):
        an oncoming one at its top speed towards it; a same-direction one at either end of its lane's speeds. A vehicle
        whose speed was measured may reach ``highest_mps`` (its own top may be above its lane's) and stand still."""
        b = self.bounds
        av_low, av_high = self.aging_mps
        if lane is Lane.RIGHT:
            return (b.oncoming_mps.high_mps if highest_mps is None else highest_mps) + av_high
        low, high = (b.same_mps.low_mps, b.same_mps.high_mps) if highest_mps is None else (0.0, highest_mps)
        return max(high - av_low, av_high - low)

    def age_m(self, lane: Lane, highest_mps: float | None = None) -> float:
        """How far a vehicle of ``lane`` may move against the AV while the snapshot ages by the bounds' ``latency_s``
        (the plan acts that much later): ``latency_s`` x ``closing_mps``. Every sensed vehicle's interval is widened
        by it either way (``start_error_m``) and every phantom comes that much nearer (``phantoms``); 0 without
        latency."""
        return self.bounds.latency_s * self.closing_mps(lane, highest_mps)

    def start_error_m(self, lane: Lane, highest_mps: float | None = None) -> float:
        """How far a sensed vehicle of ``lane`` may be from its reading's interval at the plan's start: the sensing
        error (none where the extents are sets that hold it: ``sensed_sets``), plus the snapshot's age (``age_m``; a
        vehicle whose speed was measured may reach ``highest_mps``). Every engine widens a sensed vehicle's interval
        by this."""
        return (0.0 if self.sensed_sets else self.bounds.sensing_error_m) + self.age_m(lane, highest_mps)

    def describe(self) -> str:
        b = self.bounds
        if self.checks is Checks.PAPER_CELLS:
            return f"the sound model's code path with the paper's cell rules (identity check), bounds {b.name}"
        view = "" if self.oncoming_view_m is None else f" (the oncoming one from {self.oncoming_view_m:g} m)"
        answers = ("whole plans" if self.commitment is None else
                   f"commitments with a proved escape: {self.commitment.describe()}")
        return (f"sound model ({answers}); bounds {b.name}: same-direction "
                f"{b.same_mps.low_mps:g}..{b.same_mps.high_mps:g} m/s, "
                f"oncoming {b.oncoming_mps.low_mps:g}..{b.oncoming_mps.high_mps:g} m/s, sensing error "
                f"{b.sensing_error_m:g} m, phantoms {'on' if b.phantoms else 'off'}{view}, followers "
                f"{'react' if b.followers_react else 'keep their speed'}"
                + (f", latency {b.latency_s:g} s (vehicles {self.age_m(Lane.LEFT):.3g} m on in the left lane, "
                   f"{self.age_m(Lane.RIGHT):.3g} m in the right)" if b.latency_s else "")
                + ("" if _rates(self.speed_change) == _rates(VEHICLE_SPEED_CHANGE) else
                   f", measured vehicles accelerate at most {self.speed_change.accel_mps2:g} and brake at most "
                   f"{self.speed_change.brake_mps2:g} m/s^2")
                + ("" if self.overtaken is Overtaken.PHYSICS else
                   ", measured same-direction vehicles do not speed up while the AV is in the passing lane")
                + (f", a sideways move under way at the start (both lanes for up to {self.sideways_s:g} s)"
                   if self.sideways_s else "")
                + (f", planned from the reference the car stood {self.sensors_ahead_m:g} m ahead of"
                   if self.sensors_ahead_m else "")
                + (", vehicles sensed as sets that hold the sensing error" if self.sensed_sets else "")
                + (", the plan's AV the proved reference, at its speed while the snapshot ages"
                   if self.from_reference else ""))


#: The keys of a scenario file's ``bounds`` table (and the command line's options of the same names).
BOUNDS_KEYS = ("profile", "same_mps", "oncoming_mps", "sensing_error_m", "phantoms", "av_speed_mps", "followers_react",
               "oncoming_view_m", "latency_s", "semantics", "commit_max", "escapes", "accel_mps2", "brake_mps2",
               "overtaken", "sideways_s", "sensors_ahead_m", "sensed_sets", "from_reference")
#: How near the AV an aged phantom may come (``Sound.phantoms``): never onto it (Spin reads a phantom at 0 as none).
PHANTOM_NEAREST_M = 1e-3


def sound_from(base: Sound | None, profile_name: str | None = None, same: object = None, oncoming: object = None,
               sensing_error_m: object = None, phantoms: bool | None = None, av_speed_mps: object = None,
               where: str = "--", followers_react: bool | None = None, oncoming_view_m: object = None,
               latency_s: object = None, semantics: object = None, commit_max: object = None,
               escapes: object = None, accel_mps2: object = None, brake_mps2: object = None,
               overtaken: object = None, sideways_s: object = None, sensors_ahead_m: object = None,
               sensed_sets: object = None, from_reference: object = None) -> Sound:
    """The sound model from a base (a file's, or None: the default profile, under the commitment semantics), a named
    profile and overrides of its numbers and semantics; every value is checked, and bad input names the option or
    key (``where`` + its name)."""
    def key(name: str) -> str:
        return f"{where}{name.replace('_', '-')}" if where == "--" else f"{where}{name}"

    if profile_name is not None:
        bounds = profile(str(profile_name), key("bounds") if where == "--" else key("profile"))
    else:
        bounds = base.bounds if base is not None else profile(DEFAULT_PROFILE)
    changed = []
    if same is not None:
        bounds = replace(bounds, same_mps=parse_speeds(same, key("same_mps")))
        changed.append("same-direction speeds")
    if oncoming is not None:
        bounds = replace(bounds, oncoming_mps=parse_speeds(oncoming, key("oncoming_mps")))
        changed.append("oncoming speeds")
    if sensing_error_m is not None:
        bounds = replace(bounds, sensing_error_m=check_number(key("sensing_error_m"), sensing_error_m))
        changed.append("sensing error")
    if phantoms is not None:
        bounds = replace(bounds, phantoms=check_flag(key("phantoms"), phantoms, bounds.phantoms))
        changed.append("phantoms")
    if followers_react is not None:
        bounds = replace(bounds, followers_react=check_flag(key("followers_react"), followers_react,
                                                            bounds.followers_react))
        changed.append("followers_react")
    if latency_s is not None:
        bounds = replace(bounds, latency_s=check_number(key("latency_s"), latency_s))
        changed.append("latency")
    if changed:
        bounds = replace(bounds, name=f"{bounds.name} (changed: {', '.join(changed)})",
                         source=f"{bounds.source}; changed by the user: {', '.join(changed)}")
    check_bounds(bounds, key)
    start = base.start_mps if base is not None else None
    if av_speed_mps is not None:
        start = check_number(key("av_speed_mps"), av_speed_mps, high=100.0)
    view = base.oncoming_view_m if base is not None else None
    if oncoming_view_m is not None:
        view = check_view_m(key("oncoming_view_m"), oncoming_view_m)
    commitment = commitment_from(base.commitment if base is not None else COMMIT, semantics, commit_max, escapes, key)
    change = speed_change_from(base.speed_change if base is not None else VEHICLE_SPEED_CHANGE, accel_mps2,
                               brake_mps2, key)
    behaves = base.overtaken if base is not None else Overtaken.PHYSICS
    if overtaken is not None:
        behaves = parse_overtaken(overtaken, key("overtaken"))
    moving_s = base.sideways_s if base is not None else 0.0
    if sideways_s is not None:
        moving_s = check_sideways_s(key("sideways_s"), sideways_s, base.tracking if base is not None else TRACKING)
    ahead_m = base.sensors_ahead_m if base is not None else 0.0
    if sensors_ahead_m is not None:
        ahead_m = check_sensors_ahead_m(key("sensors_ahead_m"), sensors_ahead_m,
                                        base.tracking if base is not None else TRACKING)
    sets = check_flag(key("sensed_sets"), sensed_sets, base.sensed_sets if base is not None else False)
    on_ref = check_flag(key("from_reference"), from_reference, base.from_reference if base is not None else False)
    if base is None:
        return Sound(bounds, start_mps=start, oncoming_view_m=view, commitment=commitment, speed_change=change,
                     overtaken=behaves, sideways_s=moving_s, sensors_ahead_m=ahead_m, sensed_sets=sets,
                     from_reference=on_ref)
    return replace(base, bounds=bounds, start_mps=start, oncoming_view_m=view, commitment=commitment,
                   speed_change=change, overtaken=behaves, sideways_s=moving_s, sensors_ahead_m=ahead_m,
                   sensed_sets=sets, from_reference=on_ref)


def check_flag(where: str, value: object, default: bool) -> bool:
    """A true-or-false option or key (None: ``default``); anything else is bad input naming it."""
    if value is None:
        return default
    if not isinstance(value, bool):
        raise OptionError(where, value, "must be true or false")
    return value


def check_sideways_s(where: str, value: object, tracking: Tracking = TRACKING) -> float:
    """A sideways move's time left at the snapshot: from 0 (none) to the whole move, ``Tracking.lateral_s``."""
    return check_number(where, value, high=tracking.lateral_s)


def check_sensors_ahead_m(where: str, value: object, tracking: Tracking = TRACKING) -> float:
    """How far the sensors stood ahead of the plan's reference: within the envelope's position error either way
    (a car farther off its reference is planned from where it is)."""
    return check_number(where, value, low=-tracking.position_m, high=tracking.position_m)


def _rates(change: SpeedChange) -> tuple[float, float]:
    return change.accel_mps2, change.brake_mps2


def speed_change_from(base: SpeedChange, accel_mps2: object, brake_mps2: object,
                      key: Callable[[str], str]) -> SpeedChange:
    """``base`` with the acceleration bounds given (each above 0, finite), its source saying which the user set."""
    if accel_mps2 is None and brake_mps2 is None:
        return base
    values = {}
    for name, value, kept in (("accel_mps2", accel_mps2, base.accel_mps2), ("brake_mps2", brake_mps2,
                                                                            base.brake_mps2)):
        values[name] = kept if value is None else check_number(key(name), value, positive=True)
    changed = ", ".join(n for n, v in (("a_max", accel_mps2), ("b_max", brake_mps2)) if v is not None)
    return SpeedChange(values["accel_mps2"], values["brake_mps2"], f"{base.source}; {changed} set by the user")


def commitment_from(base: Commitment | None, semantics: object, commit_max: object, escapes: object,
                    key: Callable[[str], str]) -> Commitment | None:
    """The semantics ``base`` has, changed by the options or keys given: ``semantics`` (``commit`` or ``whole``),
    the most actions committed to, the escapes allowed (either of the last two asks for the commitment semantics;
    with ``whole`` they are bad input)."""
    chosen = None if semantics is None else parse_semantics(semantics, key("semantics"))
    if chosen is Semantics.WHOLE:
        for name, value in (("commit_max", commit_max), ("escapes", escapes)):
            if value is not None:
                raise OptionError(key(name), value, "applies to the commitment semantics, not to whole plans")
        return None
    if chosen is None and commit_max is None and escapes is None:
        return base
    found = base or COMMIT
    if commit_max is not None:
        found = replace(found, most_actions=parse_most_actions(commit_max, key("commit_max")))
    if escapes is not None:
        found = replace(found, escapes=parse_escape_kinds(escapes, key("escapes")))
    return found


def check_view_m(where: str, value: object) -> float:
    """How far a snapshot saw the oncoming lane: above 0, at most the front-right sensor's range."""
    return check_number(where, value, high=SENSORS.right_range_m, positive=True)


def sound_from_table(table: object, where: str = "bounds") -> Sound:
    """The sound model a scenario file's ``bounds`` table states (every key optional; the profile defaults to
    ``default``); an unknown key or a bad value names ``bounds.<key>``."""
    if not isinstance(table, dict):
        raise OptionError(where, table, f"must be a table of {', '.join(BOUNDS_KEYS)}")
    for name in table:
        if name not in BOUNDS_KEYS:
            raise OptionError(f"{where}.{name}", table[name], f"unknown key (allowed: {', '.join(BOUNDS_KEYS)})")
    return sound_from(None, table.get("profile"), table.get("same_mps"), table.get("oncoming_mps"),
                      table.get("sensing_error_m"), table.get("phantoms"), table.get("av_speed_mps"), f"{where}.",
                      table.get("followers_react"), table.get("oncoming_view_m"), table.get("latency_s"),
                      table.get("semantics"), table.get("commit_max"), table.get("escapes"), table.get("accel_mps2"),
                      table.get("brake_mps2"), table.get("overtaken"), table.get("sideways_s"),
                      table.get("sensors_ahead_m"), table.get("sensed_sets"), table.get("from_reference"))


def sound_to_table(sound: Sound) -> dict[str, object]:
    """A sound model as a scenario file's ``bounds`` table (inverse of ``sound_from_table``)."""
    b = sound.bounds
    table: dict[str, object] = {"same_mps": [b.same_mps.low_mps, b.same_mps.high_mps],
                                "oncoming_mps": [b.oncoming_mps.low_mps, b.oncoming_mps.high_mps],
                                "sensing_error_m": b.sensing_error_m, "phantoms": b.phantoms,
                                "followers_react": b.followers_react}
    if b.latency_s:
        table["latency_s"] = b.latency_s
    if sound.start_mps is not None:
        table["av_speed_mps"] = sound.start_mps
    if sound.oncoming_view_m is not None:
        table["oncoming_view_m"] = sound.oncoming_view_m
    c = sound.commitment
    if c is None:  # a table without the key is the commitment semantics
        table["semantics"] = Semantics.WHOLE.value
    if c is not None and c.most_actions is not None:
        table["commit_max"] = c.most_actions
    if c is not None and c.escapes != COMMIT.escapes:
        table["escapes"] = [k.value for k in c.escapes]
    if _rates(sound.speed_change) != _rates(VEHICLE_SPEED_CHANGE):
        table["accel_mps2"], table["brake_mps2"] = sound.speed_change.accel_mps2, sound.speed_change.brake_mps2
    if sound.overtaken is not Overtaken.PHYSICS:
        table["overtaken"] = sound.overtaken.value
    if sound.sideways_s:
        table["sideways_s"] = sound.sideways_s
    if sound.sensors_ahead_m:
        table["sensors_ahead_m"] = sound.sensors_ahead_m
    if sound.sensed_sets:
        table["sensed_sets"] = True
    if sound.from_reference:
        table["from_reference"] = True
    return table


@dataclass(frozen=True, slots=True)
class Vehicle:
    """A vehicle of the sound model: where its centre can be at the plan's start, metres ahead of the AV's."""

    lane: Lane  # its lane: left (same direction) or right (oncoming)
    index: int | None  # into the scenario's tuple of that lane; None: a phantom
    lo_m: float
    hi_m: float
    name: str
    #: its own speed interval and dynamics (``spec.dynamics``), when its speed was measured; None: its lane's speeds
    dynamics: Dynamics | None = None


@dataclass(frozen=True, slots=True)
class Violation:
    """Why a step (or a start, or a continuation) breaks the specification: the worst case found."""

    conflict: Conflict
    vehicle: Vehicle
    time_s: float  # when, on the plan's clock
    gap_m: float  # the smallest bumper-to-bumper gap a motion within the bounds reaches
    required_m: float  # the gap the specification requires at that instant's worst closing speed

    def describe(self) -> str:
        return (f"{self.conflict.value} conflict with {self.vehicle.name} at t = {self.time_s:.2f} s: the gap can "
                f"be {self.gap_m:.2f} m where {self.required_m:.2f} m is required")


def vehicles(lane: Lane, left: tuple[int, ...], right: tuple[int, ...], grid: Grid, sound: Sound,
             left_m: tuple[Extent, ...] | None = None, right_m: tuple[Extent, ...] | None = None,
             left_mps: tuple[Speed, ...] | None = None, right_mps: tuple[Speed, ...] | None = None) -> tuple[
        Vehicle, ...]:
    """Every vehicle of a scenario (the AV starting in ``lane``) as an interval (``sensed_extents`` widened by the
    sensing error, unless the extents are sets that hold it, and the snapshot's age: ``Sound.start_error_m``), then
    the phantoms. A vehicle whose speed was
    measured (``left_mps``, ``right_mps``) moves by its own dynamics (``measured_dynamics``)."""
    out = []
    same, oncoming = sensed_extents(lane, left, right, grid, left_m, right_m)
    for key, cells, extents, speeds in ((Lane.LEFT, left, same, left_mps), (Lane.RIGHT, right, oncoming, right_mps)):
        for i, (cell, (lo, hi)) in enumerate(zip(cells, extents, strict=True)):
            own = None if speeds is None else measured_dynamics(sound, key, speeds[i])
            e = sound.start_error_m(key, None if own is None else own.highest_mps)
            out.append(Vehicle(key, i, lo - e, hi + e, f"{key.value}_lane[{i}] (cell {cell})",
                               None if own is None else own.aged(sound.bounds.latency_s)))
    for p in sound.phantoms():  # the whole unseen stretch: from the view's edge outwards
        out.append(Vehicle(p.lane, None, *p.stretch_m, f"phantom ({p.why}, {p.dx_m:+g} m)"))
    return tuple(out)


def scenario_vehicles(scenario: Scenario) -> tuple[Vehicle, ...]:
    """``vehicles`` of ``scenario`` under its own sound model: what it sensed of each vehicle's place and speed."""
    s, sound = scenario, scenario.sound
    if sound is None:
        raise ValueError("the scenario has no sound model")
    return vehicles(s.lane, s.left_lane, s.right_lane, s.grid, sound, s.left_m, s.right_m, s.left_mps, s.right_mps)


def hold_floor_mps(scenario: Scenario) -> float:
    """The speed ``scenario``'s minimal-risk manoeuvre brakes to (``slowest_ahead_mps`` of its vehicles: a standstill
    where a same-direction vehicle's speed was measured, else its lane's slowest): every engine's table of it is
    built for that speed (``spec.windows.sound_table``)."""
    assert scenario.sound is not None
    return slowest_ahead_mps(scenario.sound, scenario_vehicles(scenario))


def measured_dynamics(sound: Sound, lane: Lane, speed_mps: Speed) -> Dynamics:
    """A vehicle of ``lane`` whose speed was measured in ``speed_mps`` at the snapshot: it may brake to a standstill
    at any instant and accelerate up to its lane's top speed (``Bounds``' stated one), at ``Sound.speed_change``."""
    top = (sound.bounds.same_mps if lane is Lane.LEFT else sound.bounds.oncoming_mps).high_mps
    return Dynamics(speed_mps, top, sound.speed_change)


def slowest_ahead_mps(sound: Sound, vehicles: tuple[Vehicle, ...]) -> float:
    """The slowest a same-direction vehicle may come to drive, the speed the minimal-risk manoeuvre holds: a
    standstill where one's speed was measured (it may brake to a stop at any instant), else its lane's slowest."""
    if any(v.dynamics is not None for v in vehicles if v.lane is Lane.LEFT):
        return 0.0
    return sound.bounds.same_mps.low_mps


def rear_binds(bounds: Bounds, slowest_mps: float, follower: Vehicle | None = None) -> bool:
    """Whether the AV's followers (or ``follower``) are in conflict (``Conflict.BEHIND``) while its reference drives
    no faster than ``slowest_mps``: only where followers keep their speed whatever the AV does, and only while the
    reference is slower than a follower may be (its lane's top; a measured one's own, which may be above it). At or
    above that speed the reference never closes on a follower, and the car's own error is the envelope's position
    bound; below it, a follower at its fastest closes in and must be far enough behind for the specification's gap
    (``SoundRules._behind_allow``, the cut-in's threshold)."""
    top = bounds.same_mps.high_mps if follower is None else top_mps(bounds, follower)
    return not bounds.followers_react and slowest_mps < top - CLOSING_EPS_MPS


def held_windows_s(sound: Sound, lane: Lane, actions: Sequence[Action]) -> tuple[tuple[float, float], ...]:
    """The windows of a plan from ``lane`` in which measured same-direction vehicles hold their speed: its passing
    windows (``spec.dynamics.passing_windows_s``) under ``Overtaken.NO_ACCELERATION``, none under physics."""
    return passing_windows_s(lane, actions) if sound.overtaken is Overtaken.NO_ACCELERATION else ()


def held_vehicle(v: Vehicle, windows_s: tuple[tuple[float, float], ...], t_s: float) -> Vehicle:
    """``v`` as a plan's assumptions take it at ``t_s``: within one of ``windows_s`` (``held_windows_s``), a measured
    same-direction vehicle that has not sped up since the window began; else ``v`` itself."""
    if v.dynamics is None or v.lane is not Lane.LEFT:
        return v
    for t0, t1 in windows_s:
        if t0 <= t_s <= t1:
            return replace(v, dynamics=v.dynamics.held_from(t0))
    return v


def top_mps(bounds: Bounds, v: Vehicle) -> float:
    """The fastest ``v`` may ever drive along its direction: its lane's top, or a measured vehicle's own top when
    that is higher (``Dynamics.highest_mps``)."""
    top = bounds.speeds(v.lane).high_mps
    return top if v.dynamics is None else max(top, v.dynamics.highest_mps)


def clear_ahead_from_m(x0_m: float, sound: Sound) -> float:
    """The AV in the left lane at ``x0_m``: the least centre position from which a same-lane vehicle can be clear ahead
    of some position of the AV (bumper to bumper with its rearmost, its envelope's position error taken). Short of it,
    a vehicle is behind the AV or touching every position of it."""
    return x0_m - sound.tracking.position_m + sound.safety.vehicle_length_m


def follower_limit_m(x0_m: float, sound: Sound) -> float:
    """At a plan's start, the AV in the left lane at ``x0_m``: a same-direction vehicle whose every position is short
    of this follows the AV (a lane keeps its order), and the start has no conflict with it.

    Where followers brake for the AV (``Bounds.followers_react``), that is every vehicle that cannot be clear ahead of
    any position of the AV (its envelope's position error taken): it is behind the AV, or touching it, which is a
    collision already happened (``spec.assumptions``: nothing touches the AV at a snapshot), and a rear-end is the
    follower's to avoid. Where they keep their speed, the car's own drift back within its envelope must not reach one
    (``rear_binds`` exempts a follower while the reference is not slower than it): bumpers clear behind every position
    of the AV.

    A vehicle short of neither this nor clear ahead with its gap breaks the specification at the start
    (``start_violation``), an answer of its own, never a plan (``spec.answers.Status.UNSAFE_START``). So where
    followers react, the vehicle in the cell behind the AV's, or one measured at the least gap behind it, follows."""
    if sound.bounds.followers_react:
        return clear_ahead_from_m(x0_m, sound)
    return x0_m - sound.tracking.position_m - sound.safety.vehicle_length_m


Extent = tuple[float, float]  # where a vehicle's centre can be, metres ahead of the AV's (negative: behind)


def sensed_extents(lane: Lane, left: tuple[int, ...], right: tuple[int, ...], grid: Grid,
                   left_m: tuple[Extent, ...] | None = None,
                   right_m: tuple[Extent, ...] | None = None) -> tuple[list[Extent], list[Extent]]:
    """Where each sensed vehicle's centre can be at the snapshot, before the sensing error (same-direction, oncoming):
    what the snapshot measured (``Scenario.left_m``, ``right_m``) where it says, else anywhere in its cell
    (``spec.cells``). Every engine reads a vehicle's interval from here (Spin through its scenario values)."""
    same = list(left_m) if left_m is not None else [left_extent_m(c, lane, grid) for c in left]
    oncoming = list(right_m) if right_m is not None else [oncoming_extent_m(c, grid) for c in right]
    return same, oncoming


def reach_m(v: Vehicle, bounds: Bounds, t_s: float) -> tuple[float, float]:
    """Where ``v`` can be ``t_s`` after the snapshot under ``bounds``: its start interval grown by its lane's speeds,
    or by its own dynamics (what ``SoundRules.same_low`` and its three twins compute on the hot path, one end at a
    time)."""
    if v.dynamics is not None:
        least, most = v.dynamics.travel_m(t_s)
        return (v.lo_m + least, v.hi_m + most) if v.lane is Lane.LEFT else (v.lo_m - most, v.hi_m - least)
    if v.lane is Lane.LEFT:
        same = bounds.same_mps
        return v.lo_m + same.low_mps * t_s, v.hi_m + same.high_mps * t_s
    onc = bounds.oncoming_mps
    return v.lo_m - onc.high_mps * t_s, v.hi_m - onc.low_mps * t_s


class SoundState(NamedTuple):
    """A state of the sound model: the AV's lane, its lane changes and steps so far, the time elapsed and its nominal
    advance (both whole grid units: time units, cells), and the speeds its envelope depends on. A named tuple, not a
    frozen dataclass: searches build hundreds of thousands a second, at a tenth of a frozen dataclass's cost."""

    lane: Lane
    lane_changes: int
    steps: int
    t_units: int  # time since the plan's start, in the grid's time units
    d_cells: int  # the paper's AV's advance (instant speed changes), in cells
    first_mps: float | None  # the plan's first action's speed (its ramp starts at once), None before it
    last_mps: float | None  # the speed of the action just finished, None at the start
    moved: Lane | None = None  # the lane the action just finished moved into (a ramp after it may meet its move)
    #: The same-direction vehicles (places in ``SoundRules.same``) certainly behind the AV when it last got into the
    #: left lane: they follow it from then on (a lane keeps its order). None: since the start (classified there).
    followers: frozenset[int] | None = None
    #: When the AV started its move into the passing lane it is in, in time units (``Overtaken.NO_ACCELERATION``:
    #: measured same-direction vehicles do not speed up from then until it is back). None: in the left lane, out
    #: there since the start, or no such profile.
    out_units: int | None = None

    def key(self) -> tuple[object, ...]:
        """What the future depends on: everything but the step count (a search at the least depth keeps it)."""
        return (self.lane, self.lane_changes, self.t_units, self.d_cells, self.first_mps, self.last_mps, self.moved,
                self.followers, self.out_units)


def advance(state: SoundState, action: Action, grid: Grid, speed_mps: float) -> SoundState:
    """The state after ``action`` at ``speed_mps`` (its effect: lane, counts, time and nominal advance in whole grid
    units; every vehicle moves with its lane's bounds, so nothing else changes)."""
    rule = ACTION_RULES[action]
    units = grid.units(action)
    return SoundState(rule.to_lane or state.lane, state.lane_changes + int(rule.changes_lane), state.steps + 1,
                      state.t_units + units, state.d_cells + units - grid.left_shift(action),
                      speed_mps if state.first_mps is None else state.first_mps, speed_mps, rule.to_lane,
                      state.followers, state.out_units)


@dataclass(frozen=True, slots=True)
class Bounded:
    """A piece of the reference with its three thresholds (value, time reached): the least start ``lo`` of a
    same-direction vehicle held to AHEAD, the least ``lo`` of an oncoming one not yet past, the most ``hi`` of a
    same-direction one that the AV cuts in ahead of."""

    piece: Piece
    ahead: tuple[float, float]
    oncoming: tuple[float, float]
    behind: tuple[float, float]
    rear: bool = False  # followers are in conflict over this piece (``rear_binds``): ``behind`` holds for them too

    def shifted(self, dt_s: float, dx_m: float, bounds: Bounds) -> Bounded:
        """The same piece ``dt_s`` later and ``dx_m`` farther (every threshold is a reference position less or more
        a vehicle's speed times the time: it moves with both)."""
        p, same, onc = self.piece, bounds.same_mps, bounds.oncoming_mps
        return Bounded(Piece(p.t0_s + dt_s, p.t1_s + dt_s, p.x0_m + dx_m, p.v0_mps, p.acc_mps2),
                       (self.ahead[0] + dx_m - same.low_mps * dt_s, self.ahead[1] + dt_s),
                       (self.oncoming[0] + dx_m + onc.high_mps * dt_s, self.oncoming[1] + dt_s),
                       (self.behind[0] + dx_m - same.high_mps * dt_s, self.behind[1] + dt_s), self.rear)


@dataclass(frozen=True, slots=True)
class Segment:
    """A stretch of a window with one occupancy: the lanes the AV is in, and whether it is entering the left one."""

    t0_s: float
    t1_s: float
    lanes: frozenset[Lane]
    entering_left: bool  # vehicles of the left lane are classified: certainly ahead, or certainly behind
    at_start: bool = False  # the plan's start: one short of ``follower_limit_m`` is a follower, not a cut-in


Shapes = dict[tuple[float, Action | None, Lane, Lane | None], list[tuple[Segment, list[Bounded]]]]


@functools.lru_cache(maxsize=16)
def _shapes(sound: Sound, grid: Grid, hold_floor_mps: float) -> Shapes:
    """The windows' shapes (``SoundRules.window``), shared by every scenario under the same assumptions, grid and
    minimal-risk hold speed (``slowest_ahead_mps``): a shape depends on the speeds, the action, the lane and the move
    before it, never on the vehicles."""
    return {}


class SoundRules:
    """The sound model on one scenario: its vehicles and every rule over sound states."""

    def __init__(self, sound: Sound, lane: Lane, left: tuple[int, ...], right: tuple[int, ...], grid: Grid,
                 targets: tuple[int, ...], given: tuple[Vehicle, ...] | None = None,
                 left_m: tuple[Extent, ...] | None = None, right_m: tuple[Extent, ...] | None = None,
                 left_mps: tuple[Speed, ...] | None = None, right_mps: tuple[Speed, ...] | None = None,
                 hold_floor_mps: float | None = None) -> None:
        """``given``: the vehicles as intervals, when not the scenario's own (``vehicles``, of the cells or of what
        the snapshot measured, ``left_m`` and ``right_m``, and their speeds, ``left_mps`` and ``right_mps``); a
        measurement that moves one of them passes them here. ``hold_floor_mps``: the speed the minimal-risk
        manoeuvre brakes to when not the vehicles' own (``slowest_ahead_mps``): the engines' tables, which hold no
        vehicle, ask it of scenarios whose vehicles may stop."""
        self.sound, self.grid, self.targets = sound, grid, targets
        #: the lane the AV ends its sideways move under way at the start in, and until when it is in both lanes
        #: (``Sound.sideways_s``; 0: no move under way)
        self.lane, self.move_s = lane, sound.sideways_s
        self.vehicles = vehicles(lane, left, right, grid, sound, left_m, right_m, left_mps, right_mps) \
            if given is None else given
        self.same = tuple(v for v in self.vehicles if v.lane is Lane.LEFT)
        self.oncoming = tuple(v for v in self.vehicles if v.lane is Lane.RIGHT)
        self.sensed_same = {v.index: v for v in self.same if v.index is not None}
        self.unit_s, self.cell_m = float(grid.time_unit_s), grid.cell
        self.speeds = {a: action_speed_mps(a, grid) for a in Action}
        self.start_mps = grid.speed if sound.start_mps is None else sound.start_mps
        #: The most a ramp centred on a boundary can put the AV behind its nominal position there (the ramp into a
        #: slower action starts half a ramp early): a lower bound on where the AV is at a boundary, whatever follows.
        self.dip_m = max((v1 - v2) * ramp_s(v1, v2) / 8 for v1 in self.speeds.values() for v2 in self.speeds.values()
                         if v1 > v2)
        #: The most the AV's nominal advance can gain on a same-direction vehicle at its highest speed in one action,
        #: and the most the first ramp can add to it (``beyond_reach``).
        #: The speed the minimal-risk manoeuvre brakes to (``slowest_ahead_mps``).
        self.hold_floor_mps = slowest_ahead_mps(sound, self.vehicles) if hold_floor_mps is None else hold_floor_mps
        #: The least speed a same-direction vehicle's fastest motion ever drives at (its lane's top; a measured one's
        #: highest measured speed, from which it only speeds up).
        high = min([sound.bounds.same_mps.high_mps] + [v.dynamics.speed_mps[1] for v in self.vehicles
                                                          if v.lane is Lane.LEFT and v.dynamics is not None])
        self.gain_per_action_m = max((grid.units(a) - grid.left_shift(a)) * self.cell_m
                                     - high * grid.units(a) * self.unit_s for a in Action)
        self.first_ramp_m = {v: abs(ramp_gain_m(self.start_mps, v)) for v in self.speeds.values()}
        self.most_first_ramp_m = max(self.first_ramp_m.values())
        #: The oncoming phantoms (the unseen stretch beyond the range), the nearest one's near end, the least
        #: oncoming gap and the AV's fastest speed (``hopeless``).
        self.oncoming_phantoms = tuple(v for v in self.oncoming if math.isinf(v.hi_m))
        self.same_phantoms_ahead = tuple(v for v in self.same if math.isinf(v.hi_m))
        self.nearest_phantom_m = max((v.lo_m for v in self.oncoming_phantoms), default=math.inf)
        self.least_oncoming_gap_m = sound.safety.required_gap_m(sound.tracking.speed_mps
                                                                + sound.bounds.oncoming_mps.high_mps)
        self.fastest_mps = max(max(self.speeds.values()), self.start_mps)
        self._goal_m: tuple[GoalRule | None, float | None] = (None, None)
        self._steps: dict[tuple[tuple[object, ...], Action, Action | None], Violation | None] = {}
        self._ends: dict[tuple[object, ...], Violation | None] = {}  # continuation_violation, by state key
        self._at_boundary: dict[tuple[int, int, float | None, float | None], float] = {}
        self._relative = _shapes(sound, grid, self.hold_floor_mps)
        self._start_followers: frozenset[int] | None = None
        #: Whether measured same-direction vehicles hold their speed while the AV is in the passing lane
        #: (``Overtaken.NO_ACCELERATION``, and a vehicle it speaks of): states then carry ``out_units``.
        self.held_passing = sound.overtaken is Overtaken.NO_ACCELERATION and any(
            v.dynamics is not None for v in self.same)

    def key(self, state: SoundState) -> tuple[object, ...]:
        """What a search tells states apart by (``SoundState.key``)."""
        return state.key()

    # -- the AV's reference over a window ---------------------------------------------------------------------
    def boundary_m(self, state: SoundState) -> float:
        """Where the AV's reference is at ``state``'s boundary (``reference(state, None)`` there; it depends on the
        time, the nominal advance and the speeds alone: the goal and the prunes ask it of every state, once each)."""
        asked = (state.t_units, state.d_cells, state.first_mps, state.last_mps)
        found = self._at_boundary.get(asked)
        if found is None:
            if len(self._at_boundary) >= MEMO_ENTRIES:
                self._at_boundary.clear()
            found = self._at_boundary[asked] = self.reference(state, None).position_m(state.t_units * self.unit_s)
        return found

    def nearest_target_m(self, goal: GoalRule) -> float | None:
        """``goal.nearest_target_m`` as a float (converted once per goal a search asks: the prunes ask it of every
        state)."""
        if self._goal_m[0] is not goal:
            self._goal_m = (goal, None if goal.nearest_target_m is None else float(goal.nearest_target_m))
        return self._goal_m[1]

    def reference(self, state: SoundState, action: Action | None) -> Reference:
        """The reference from ``state``'s boundary on, into ``action`` (None: the minimal-risk manoeuvre)."""
        return self._reference(state.t_units * self.unit_s, state.d_cells * self.cell_m, state.first_mps,
                               state.last_mps, action, self.start_mps)

    def _reference(self, t_s: float, nominal_m: float, first_mps: float | None, last_mps: float | None,
                   action: Action | None, start_mps: float) -> Reference:
        if first_mps is None:
            first_mps = self.speeds[action] if action is not None else start_mps
        before = last_mps if last_mps is not None else first_mps
        if action is None:
            hold = self.sound.minimal_risk.hold_mps(before, self.hold_floor_mps)
            ramp = self.sound.minimal_risk.ramp(t_s, before, hold)
        elif last_mps is None or self.speeds[action] == before:
            ramp = None
        else:
            r = ramp_s(before, self.speeds[action])
            ramp = Ramp(t_s - r / 2, r, self.speeds[action] - before)
        return Reference(start_mps, first_mps, t_s, nominal_m, before, ramp)

    def _segments(self, lane: Lane, ref: Reference, action: Action | None, moved: Lane | None) -> list[Segment]:
        """The window of ``action`` (None: the minimal-risk manoeuvre, in lane) from the boundary ``ref`` starts
        at: the ramp into it (in the lane the AV is in, or in both while the sideways move of the action before it,
        ``moved`` into a lane, still runs), the sideways move (both lanes), the rest (the lane it ends in)."""
        t_s = ref.boundary_s
        if action is None:
            end_s = t_s + (ref.ramp.duration_s if ref.ramp is not None else 0.0)
            return [Segment(t_s, end_s, frozenset({lane}), False)]
        rule = ACTION_RULES[action]
        end_s = t_s + float(rule.duration_s)
        out = []
        if ref.ramp is not None and ref.ramp.start_s < t_s:
            ramp_from = ref.ramp.start_s
            if moved is not None:
                change = Action.LEFT_LANE_CHANGE if moved is Lane.LEFT else Action.RIGHT_LANE_CHANGE
                duration = float(ACTION_RULES[change].duration_s)
                move_end = t_s - duration + min(self.sound.tracking.lateral_s, duration)
                if ramp_from < move_end:
                    out.append(Segment(ramp_from, move_end, frozenset(Lane), moved is Lane.LEFT))
                    ramp_from = move_end
            out.append(Segment(ramp_from, t_s, frozenset({lane}), False))
        if rule.to_lane is None:
            out.append(Segment(t_s, end_s, frozenset({lane}), False))
            return out
        move_end = t_s + min(self.sound.tracking.lateral_s, float(rule.duration_s))
        out.append(Segment(t_s, move_end, frozenset(Lane), rule.to_lane is Lane.LEFT))
        if move_end < end_s:
            out.append(Segment(move_end, end_s, frozenset({rule.to_lane}), False))
        return out

    def window(self, state: SoundState, action: Action | None) -> list[tuple[Segment, list[Bounded]]]:
        """The window of ``action`` from ``state``, cut into segments of one occupancy and pieces with thresholds.

        Once the first ramp has run out, a window is the same shape wherever it starts (the reference is the
        nominal position plus the first ramp's constant gain, plus the ramp at the boundary): it is computed
        once per (speed before, action) and moved in time and place."""
        ref = self.reference(state, action)
        if self.is_early(ref):
            segments = self._segments(state.lane, ref, action, state.moved)
            if self.move_s > 0:
                segments = self._moving(segments, action is None)
            return [(seg, [self._bounded(p) for p in ref.pieces(seg.t0_s, seg.t1_s)]) for seg in segments]
        shape = self.relative_window(ref.before_mps, action, state.lane, state.moved)
        dt, dx = ref.boundary_s, ref.nominal_m + ramp_gain_m(ref.start_mps, ref.first_mps)
        bounds = self.sound.bounds
        return [(Segment(seg.t0_s + dt, seg.t1_s + dt, seg.lanes, seg.entering_left),
                 [b.shifted(dt, dx, bounds) for b in pieces]) for seg, pieces in shape]

    def is_early(self, ref: Reference) -> bool:
        """Whether a window from ``ref`` is computed as it is, never moved from a shape: while the first ramp runs
        (``early``), or while the sideways move under way at the start does (``Sound.sideways_s``)."""
        return early(ref) or window_start_s(ref) < self.move_s

    def start_segment(self) -> Segment:
        """The start, an instant: in the scenario's lane, or in both while a sideways move is under way; a start in
        the left lane, or partly in it during a move either way, holds every vehicle of it clear ahead or a follower
        (``_check_entering``): none beside the AV."""
        moving = self.move_s > 0
        lanes = frozenset(Lane) if moving else frozenset({self.lane})
        return Segment(0.0, 0.0, lanes, self.lane is Lane.LEFT or moving, at_start=True)

    def _moving(self, segments: list[Segment], continuation: bool) -> list[Segment]:
        """``segments`` with the sideways move under way at the start laid over them: until ``move_s`` the AV is in
        both lanes, entering the left one when it moves into it (every vehicle there certainly ahead or certainly
        behind, a cut-in's gap). A continuation (the plan's last window) runs on in its lane to the move's end, so
        that every instant of the move is in some window."""
        out: list[Segment] = []
        for seg in segments:
            if seg.t0_s >= self.move_s:
                out.append(seg)
                continue
            out.append(Segment(seg.t0_s, min(seg.t1_s, self.move_s), frozenset(Lane),
                               seg.entering_left or self.lane is Lane.LEFT))
            if seg.t1_s > self.move_s:
                out.append(replace(seg, t0_s=self.move_s))
        if continuation and out[-1].t1_s < self.move_s:
            out.append(Segment(out[-1].t1_s, self.move_s, frozenset(Lane), self.lane is Lane.LEFT))
        return out

    def relative_window(self, before_mps: float, action: Action | None, lane: Lane, moved: Lane | None) -> list[
            tuple[Segment, list[Bounded]]]:
        """The window's shape from a boundary at time 0 and place 0 (``window``), once per speed before it, action,
        lane and move before it."""
        key = (before_mps, action, lane, moved)
        shape = self._relative.get(key)
        if shape is None:
            rel = self._reference(0.0, 0.0, before_mps, before_mps, action, before_mps)
            shape = self._relative[key] = [
                (seg, [self._bounded(p) for p in rel.pieces(seg.t0_s, seg.t1_s)])
                for seg in self._segments(lane, rel, action, moved)]
        return shape

    def _bounded(self, p: Piece) -> Bounded:
        return Bounded(p, self._ahead_need(p), self._oncoming_need(p), self._behind_allow(p),
                       rear_binds(self.sound.bounds, min(p.v0_mps, p.v(p.t1_s))))

    # -- the conditions, as thresholds on a vehicle's start interval -----------------------------------------
    def _ahead_need(self, p: Piece) -> tuple[float, float]:
        """The least ``lo`` a same-direction vehicle may have to keep AHEAD safe over ``p``, and when it binds."""
        s, tr, low = self.sound.safety, self.sound.tracking, self.sound.bounds.same_mps.low_mps
        base = p.x0_m - low * p.t0_s + tr.position_m + s.vehicle_length_m
        return _max_of(p, base + s.min_gap_m, p.v0_mps - low, base + s.time_gap_s * (p.v0_mps + tr.speed_mps - low),
                       p.v0_mps - low + s.time_gap_s * p.acc_mps2)

    def _oncoming_need(self, p: Piece) -> tuple[float, float]:
        """The least ``lo`` an oncoming vehicle may have to keep ONCOMING safe over ``p``, and when it binds."""
        s, tr, high = self.sound.safety, self.sound.tracking, self.sound.bounds.oncoming_mps.high_mps
        base = p.x0_m + high * p.t0_s + tr.position_m + s.vehicle_length_m
        return _max_of(p, base + s.min_gap_m, p.v0_mps + high, base + s.time_gap_s * (p.v0_mps + tr.speed_mps + high),
                       p.v0_mps + high + s.time_gap_s * p.acc_mps2)

    def _behind_allow(self, p: Piece) -> tuple[float, float]:
        """The most ``hi`` a same-direction vehicle may have to be CUT_IN safe behind the AV over ``p``, and when."""
        s, tr, high = self.sound.safety, self.sound.tracking, self.sound.bounds.same_mps.high_mps
        base = p.x0_m - high * p.t0_s - tr.position_m - s.vehicle_length_m
        value, at = _max_of(p, -(base - s.min_gap_m), -(p.v0_mps - high),
                            -(base - s.time_gap_s * (high - p.v0_mps + tr.speed_mps)),
                            -(p.v0_mps - high + s.time_gap_s * p.acc_mps2), flip=True)
        return -value, at

    # -- positions -------------------------------------------------------------------------------------------
    def same_low(self, v: Vehicle, t_s: float) -> float:
        if v.dynamics is not None:
            return v.lo_m + v.dynamics.travel_m(t_s)[0]
        return v.lo_m + self.sound.bounds.same_mps.low_mps * t_s

    def same_high(self, v: Vehicle, t_s: float) -> float:
        if v.dynamics is not None:
            return v.hi_m + v.dynamics.travel_m(t_s)[1]
        return v.hi_m + self.sound.bounds.same_mps.high_mps * t_s

    def oncoming_low(self, v: Vehicle, t_s: float) -> float:
        if v.dynamics is not None:
            return v.lo_m - v.dynamics.travel_m(t_s)[1]
        return v.lo_m - self.sound.bounds.oncoming_mps.high_mps * t_s

    def oncoming_high(self, v: Vehicle, t_s: float) -> float:
        if v.dynamics is not None:
            return v.hi_m - v.dynamics.travel_m(t_s)[0]
        return v.hi_m - self.sound.bounds.oncoming_mps.low_mps * t_s

    def least_high(self, v: Vehicle, t_s: float) -> float:
        """``same_high`` as the prunes may take it: under ``Overtaken.NO_ACCELERATION`` the fastest motion that holds
        for every plan (a measured vehicle at its highest speed, never speeding up: any passing window may start at
        once), so an argument that such a motion cannot be passed holds for all of them."""
        if self.held_passing and v.dynamics is not None:
            return v.hi_m + v.dynamics.held_from(0.0).travel_m(t_s)[1]
        return self.same_high(v, t_s)

    def least_high_mps(self, v: Vehicle, t_s: float) -> float:
        """The speed of ``least_high``'s motion at ``t_s`` (a vehicle without a measured speed: its lane's top)."""
        if v.dynamics is None:
            return self.sound.bounds.same_mps.high_mps
        d = v.dynamics.held_from(0.0) if self.held_passing else v.dynamics
        return d.speeds_mps(t_s)[1]

    def passing_from_s(self, state: SoundState) -> float | None:
        """When the passing window ``state`` is in started (plan clock), if measured vehicles hold their speed in it
        (``held_passing``): the AV's move out, or the start when it started out there; None: no such window."""
        if not self.held_passing:
            return None
        if state.out_units is not None:
            return state.out_units * self.unit_s
        return 0.0 if state.lane is Lane.RIGHT else None

    def held_ahead(self, v: Vehicle, ref_x: float, t_s: float) -> bool:
        """Whether a same-direction vehicle is held to AHEAD at ``t_s``: when every position of it is clear ahead of
        the AV. Where the AV entered the left lane (or started in it) every vehicle was certainly ahead with its gap,
        held so ever since, or certainly behind; one behind follows the AV (a lane keeps its order) and is no
        conflict, so a vehicle not clear ahead now is one of those."""
        return self.same_low(v, t_s) - self.sound.safety.vehicle_length_m >= ref_x + self.sound.tracking.position_m

    def passed(self, v: Vehicle, ref_x: float, t_s: float) -> bool:
        """Whether an oncoming vehicle is certainly past the AV at ``t_s`` (bumpers clear for every position)."""
        return self.oncoming_high(v, t_s) + self.sound.safety.vehicle_length_m \
            <= ref_x - self.sound.tracking.position_m - EPS_M

    # -- checks ---------------------------------------------------------------------------------------------
    def _required(self, conflict: Conflict, p: Piece, t_s: float, vehicle: Vehicle | None = None) -> float:
        s, tr, b = self.sound.safety, self.sound.tracking, self.sound.bounds
        v = p.v(t_s)
        if vehicle is not None and vehicle.dynamics is not None:
            low, high = vehicle.dynamics.speeds_mps(t_s)
            same_low, same_high, onc_high = low, high, high
        else:
            same_low, same_high, onc_high = b.same_mps.low_mps, b.same_mps.high_mps, b.oncoming_mps.high_mps
        closing = {Conflict.AHEAD: v + tr.speed_mps - same_low,
                   Conflict.ONCOMING: v + tr.speed_mps + onc_high,
                   Conflict.CUT_IN: same_high - v + tr.speed_mps,
                   Conflict.BEHIND: same_high - v + tr.speed_mps}[conflict]
        return s.required_gap_m(closing)

    def _violation(self, conflict: Conflict, v: Vehicle, p: Piece, need: tuple[float, float], lo: bool,
                   nearest_m: float | None = None) -> Violation:
        """A violation: the vehicle's start interval misses the threshold ``need`` (at its lower or upper end; or at
        ``nearest_m``, the nearest position the assumptions allow, where not its lower end)."""
        short = (need[0] - (v.lo_m if nearest_m is None else nearest_m)) if lo else (v.hi_m - need[0])
        required = self._required(conflict, p, need[1], v)
        return Violation(conflict, v, need[1], required - short, required)

    def _need(self, conflict: Conflict, v: Vehicle, b: Bounded) -> tuple[float, float]:
        """The threshold ``v`` is held to over ``b``'s piece: its lane's (``Bounded``), or its own."""
        if v.dynamics is None:
            return {Conflict.AHEAD: b.ahead, Conflict.ONCOMING: b.oncoming}.get(conflict, b.behind)
        return self._own_need(conflict, v.dynamics, b.piece)

    def _own_need(self, conflict: Conflict, d: Dynamics, p: Piece) -> tuple[float, float]:
        """The threshold of ``conflict`` over ``p`` for a vehicle moving by its own dynamics: as ``_ahead_need`` and
        its twins, with the vehicle's least travel (AHEAD: braking to a stop) or its most (ONCOMING, CUT_IN, BEHIND:
        speeding up to its top) in place of its lane's speed times the time, and its speed then in the closing speed.
        The worst position and the worst speed come from one motion, so the bound is exact; over each phase of that
        motion within the piece both the reference and the vehicle's travel are quadratic (``_quad_max``). For CUT_IN
        and BEHIND the value is the most ``hi`` allowed, as ``_behind_allow``."""
        s, tr = self.sound.safety, self.sound.tracking
        length, tau, g_min = s.vehicle_length_m, s.time_gap_s, s.min_gap_m
        best = (-math.inf, p.t0_s)
        for ph in (d.slowest if conflict is Conflict.AHEAD else d.fastest):
            u0, u1 = max(p.t0_s, ph.t0_s), min(p.t1_s, ph.t1_s)
            if u1 < u0 or (u1 == u0 and p.t1_s > p.t0_s):
                continue
            x, v, acc, span = p.x(u0), p.v(u0), p.acc_mps2, u1 - u0
            dm, dv, da = ph.travel(u0), ph.speed(u0), ph.accel_mps2
            if conflict is Conflict.AHEAD:  # lo >= x + e_x + L - D + max(g_min, tau (v + e_v - V))
                c, b1, a = x + tr.position_m + length - dm, v - dv, (acc - da) / 2
                found = max(_quad_max(a, b1, c + g_min, span, u0),
                            _quad_max(a, b1 + tau * (acc - da), c + tau * (v + tr.speed_mps - dv), span, u0))
            elif conflict is Conflict.ONCOMING:  # lo >= x + e_x + L + D + max(g_min, tau (v + e_v + V))
                c, b1, a = x + tr.position_m + length + dm, v + dv, (acc + da) / 2
                found = max(_quad_max(a, b1, c + g_min, span, u0),
                            _quad_max(a, b1 + tau * (acc + da), c + tau * (v + tr.speed_mps + dv), span, u0))
            else:  # hi <= x - e_x - L - D - max(g_min, tau (V - v + e_v)): the most of its negation
                c, b1, a = -(x - tr.position_m - length - dm), -(v - dv), -(acc - da) / 2
                found = max(_quad_max(a, b1, c + g_min, span, u0),
                            _quad_max(a, b1 + tau * (da - acc), c + tau * (dv - v + tr.speed_mps), span, u0))
            best = max(best, found)
        if conflict in (Conflict.CUT_IN, Conflict.BEHIND):
            return -best[0], best[1]
        return best

    def check_segment(self, seg: Segment, pieces: list[Bounded], followers: frozenset[int] = frozenset(),
                      held_from_s: float | None = None) -> Violation | None:
        """The first violation over one segment of a window (AV occupancy fixed), or None; ``followers``: the
        vehicles that follow the AV in the left lane (no conflict); ``held_from_s``: measured same-direction vehicles
        do not speed up from then on (a passing window's start, ``passing_from_s``)."""
        if Lane.LEFT in seg.lanes:
            found = self._check_entering(pieces, not seg.at_start, held_from_s) if seg.entering_left else \
                self._check_ahead(pieces, followers)
            if found is not None:
                return found
        if Lane.RIGHT in seg.lanes:
            return self._check_oncoming(pieces)
        return None

    def _check_ahead(self, pieces: list[Bounded], followers: frozenset[int]) -> Violation | None:
        """AHEAD for every vehicle not a follower; BEHIND for the followers over the pieces where they bind."""
        for b in pieces:
            for i, v in enumerate(self.same):
                if i in followers:
                    continue
                need = self._need(Conflict.AHEAD, v, b)
                if v.lo_m < need[0] + EPS_M and self.held_ahead(v, b.piece.x0_m, b.piece.t0_s):
                    return self._violation(Conflict.AHEAD, v, b.piece, need, True)
            for i in sorted(followers):
                v = self.same[i]
                if b.rear if v.dynamics is None else rear_binds(self.sound.bounds, min(b.piece.v0_mps, b.piece.v(
                        b.piece.t1_s)), v):
                    allow = self._need(Conflict.BEHIND, v, b)
                    if v.hi_m > allow[0] - EPS_M:
                        return self._violation(Conflict.BEHIND, v, b.piece, allow, False)
        return None

    def _check_oncoming(self, pieces: list[Bounded]) -> Violation | None:
        for b in pieces:
            for v in self.oncoming:
                need = self._need(Conflict.ONCOMING, v, b)
                if v.lo_m < need[0] + EPS_M and not self.passed(v, b.piece.x0_m, b.piece.t0_s):
                    return self._violation(Conflict.ONCOMING, v, b.piece, need, True)
        return None

    def _check_entering(self, pieces: list[Bounded], margin: bool, held_from_s: float | None = None) \
            -> Violation | None:
        """Entering the left lane: each same-direction vehicle certainly ahead (AHEAD) or certainly behind (CUT_IN)
        over the whole sideways move. At the plan's start (``margin`` False) the AV is already in the lane: one
        behind need only be short of ``follower_limit_m``; it is a follower, not a cut-in.
        A move back from the passing lane under ``Overtaken.NO_ACCELERATION`` (``held_from_s``): a measured vehicle
        cut in ahead of has not sped up since the move out began."""
        lane_ahead = max(pieces, key=lambda b: b.ahead[0])
        lane_behind = min(pieces, key=lambda b: b.behind[0]) if margin else pieces[0]
        for v in self.same:
            if v.dynamics is None:
                ahead_piece, need = lane_ahead.piece, lane_ahead.ahead
                behind_piece, allow = lane_behind.piece, lane_behind.behind
            else:
                need, ahead_piece = max(((self._own_need(Conflict.AHEAD, v.dynamics, b.piece), b.piece)
                                         for b in pieces), key=lambda found: found[0][0])
                dynamics = v.dynamics
                if held_from_s is not None:
                    dynamics = dynamics.held_from(held_from_s)
                    v = replace(v, dynamics=dynamics)
                allow, behind_piece = min(((self._own_need(Conflict.CUT_IN, dynamics, b.piece), b.piece)
                                           for b in pieces), key=lambda found: found[0][0]) if margin else \
                    (lane_behind.behind, lane_behind.piece)
            if not margin:
                allow = (follower_limit_m(behind_piece.x0_m, self.sound),
                         behind_piece.t0_s)
            if v.lo_m >= need[0] + EPS_M or v.hi_m <= allow[0] - EPS_M:
                continue
            if not margin:
                return self._start_conflict(v, ahead_piece, need)
            if v.lo_m - need[0] > allow[0] - v.hi_m:  # nearer to being ahead: that conflict
                return self._violation(Conflict.AHEAD, v, ahead_piece, need, True)
            return self._violation(Conflict.CUT_IN, v, behind_piece, allow, False)
        return None

    def _start_conflict(self, v: Vehicle, p: Piece, need: tuple[float, float]) -> Violation:
        """The conflict of a same-lane vehicle that neither follows the AV nor is clear ahead of it at the start (the
        AV at ``p``'s start), named by where it can be. One that cannot be clear ahead of any position of the AV (its
        envelope's position error taken) is behind it, a lane keeping its order (``follower_limit_m``'s rule, which
        only where followers keep their speed leaves such a vehicle short of a follower): ``BEHIND``, its gap from the
        AV's rearmost position, which it may reach into (negative), the cut-in's gap required where ``rear_binds`` at
        the start speed, else bumpers clear. Any other: ``AHEAD``, its gap at least 0 (nothing touches the AV at a
        snapshot, ``spec.assumptions``)."""
        length, error_m = self.sound.safety.vehicle_length_m, self.sound.tracking.position_m
        x0 = p.x0_m
        if v.hi_m < clear_ahead_from_m(x0, self.sound):
            binds = rear_binds(self.sound.bounds, p.v0_mps, v)
            required = self._required(Conflict.BEHIND, p, p.t0_s, v) if binds else 0.0
            return Violation(Conflict.BEHIND, v, p.t0_s, x0 - error_m - length - v.hi_m, required)
        return self._violation(Conflict.AHEAD, v, p, need, True, max(v.lo_m, x0 + error_m + length))

    # -- the model's questions -------------------------------------------------------------------------------
    def start_violation(self, state: SoundState) -> Violation | None:
        """The start, an instant: the AV in its lane, every vehicle in conflict keeping its gap (one in the AV's
        lane certainly ahead, or certainly behind it); in the left lane, then as in it (``_check_ahead``): a
        follower that keeps its speed, while the AV is slower than it may be, behind as a cut-in must be (the first
        instant of every step and of the continuation asks the same: a start that breaks it has no plan because it
        is unsafe already, an answer of its own)."""
        ref = self.reference(state, None)
        seg = self.start_segment()
        pieces = [self._bounded(p) for p in ref.pieces(0.0, 0.0)]
        found = self.check_segment(seg, pieces)
        if found is None and Lane.LEFT in seg.lanes:
            found = self._check_ahead(pieces, self.followers(state, None))
        return found

    def step_violation(self, state: SoundState, action: Action, following: Action | None = None) -> Violation | None:
        """Whether ``action`` from ``state`` keeps the specification at every instant of its window (each question
        answered once: a pipeline's searches, its proof and its validation ask the same ones).

        Without ``following`` the window runs to the action's end at its own speed, whatever comes after (a search
        does not know). With it (a sequence known whole: a commitment and its escape, ``oracle.commit``) the window
        ends where the ramp into ``following``, centred on the boundary, starts: from there on the reference is that
        ramp, and ``following``'s own window (from the start of the ramp into it) checks it."""
        cut = self.cut_s(state.t_units, action, following)
        asked = (state.key(), action, following if cut is not None else None)
        if asked in self._steps:
            return self._steps[asked]
        found = None
        followers = self.followers(state, action)
        held = self.passing_from_s(state) if ACTION_RULES[action].to_lane is Lane.LEFT else None
        window = self.window(state, action)
        for seg, pieces in window if cut is None else self.cut_window(window, cut):
            found = self.check_segment(seg, pieces, followers, held)
            if found is not None:
                break
        if len(self._steps) >= MEMO_ENTRIES:
            self._steps.clear()
        self._steps[asked] = found
        return found

    def cut_s(self, t_units: int, action: Action, following: Action | None) -> float | None:
        """Where the window of ``action``, taken ``t_units`` time units into the plan, ends when ``following`` comes
        after it: the start of the ramp into it (None: no ramp, the speeds are the same, or nothing follows)."""
        if following is None or self.speeds[following] == self.speeds[action]:
            return None
        end_s = (t_units + self.grid.units(action)) * self.unit_s
        return end_s - ramp_s(self.speeds[action], self.speeds[following]) / 2

    def cut_window(self, window: list[tuple[Segment, list[Bounded]]], cut_s: float) -> list[
            tuple[Segment, list[Bounded]]]:
        """``window`` up to ``cut_s``: its segments that start before it, each clipped there."""
        return [self._clipped(seg, pieces, cut_s) for seg, pieces in window if seg.t0_s < cut_s]

    def _clipped(self, seg: Segment, pieces: list[Bounded], cut_s: float) -> tuple[Segment, list[Bounded]]:
        """A window's segment and its pieces up to ``cut_s`` (each piece's thresholds taken over what is left)."""
        if seg.t1_s <= cut_s:
            return seg, pieces
        kept = [b if b.piece.t1_s <= cut_s else self._bounded(replace(b.piece, t1_s=cut_s))
                for b in pieces if b.piece.t0_s < cut_s]
        return replace(seg, t1_s=cut_s), kept

    def after(self, state: SoundState, action: Action) -> SoundState:
        """The state after ``action`` (``advance``), with the vehicles that follow the AV once it gets into the left
        lane."""
        nxt = advance(state, action, self.grid, self.speeds[action])
        to_lane = ACTION_RULES[action].to_lane
        if to_lane is Lane.LEFT:
            return nxt._replace(followers=self.followers(state, action), out_units=None)
        if to_lane is Lane.RIGHT and self.held_passing:
            return nxt._replace(out_units=state.t_units)
        return nxt

    def followers(self, state: SoundState, action: Action | None) -> frozenset[int]:
        """The vehicles that follow the AV in the left lane during ``action`` from ``state`` (None: after it): the
        state's, or for a move into the left lane those not clear ahead at its boundary. The entering checks hold
        every vehicle certainly ahead or certainly behind over the whole sideways move, so these are the ones behind
        (as at the start, where ``start_violation`` holds them so)."""
        if action is not None and ACTION_RULES[action].to_lane is Lane.LEFT:
            t_s = state.t_units * self.unit_s
            return self._behind(self.reference(state, action).position_m(t_s), t_s)
        if state.followers is not None:
            return state.followers
        if self._start_followers is None:
            self._start_followers = self._behind(
                self._reference(0.0, 0.0, None, None, None, self.start_mps).position_m(0.0), 0.0)
        return self._start_followers

    def _behind(self, x_m: float, t_s: float) -> frozenset[int]:
        return frozenset(i for i, v in enumerate(self.same) if not self.held_ahead(v, x_m, t_s))

    def continuation_violation(self, state: SoundState) -> Violation | None:
        """A plan's last state must be safe for ever: the minimal-risk manoeuvre (brake in lane to the hold speed)
        over its ramp, and after it no conflict may close in (an oncoming vehicle not yet past an AV in the right
        lane always does; a follower that keeps its speed does when the hold speed is below it). Each state's
        answered once (a commitment's escapes, its split and its validation ask again)."""
        asked = state.key()
        if asked in self._ends:
            return self._ends[asked]
        if len(self._ends) >= MEMO_ENTRIES:
            self._ends.clear()
        found = self._ends[asked] = self._continuation(state)
        return found

    def _continuation(self, state: SoundState) -> Violation | None:
        followers = self.followers(state, None)
        window = self.window(state, None)
        for seg, pieces in window:
            found = self.check_segment(seg, pieces, followers)
            if found is not None:
                return found
        tail = window[-1][1][-1].piece
        end_s, end_x, end_v = tail.t1_s, tail.x(tail.t1_s), tail.v(tail.t1_s)
        if state.lane is Lane.RIGHT:
            for v in self.oncoming:
                if not self.passed(v, end_x, end_s):
                    return Violation(Conflict.ONCOMING, v, end_s, -math.inf, self._required(
                        Conflict.ONCOMING, tail, end_s))
            return None
        for i, v in enumerate(self.same):  # one that may come to drive slower than the AV's hold closes in for ever
            if i in followers or not self.held_ahead(v, end_x, end_s):
                continue
            lowest = 0.0 if v.dynamics is not None else self.sound.bounds.same_mps.low_mps
            if self.sound.minimal_risk.closes_in(end_v, lowest):
                return Violation(Conflict.AHEAD, v, end_s, -math.inf, self._required(Conflict.AHEAD, tail, end_s, v))
            found = self._braking_on(v, end_s, end_x, end_v)
            if found is not None:
                return found
        for i in sorted(followers):
            v = self.same[i]
            if rear_binds(self.sound.bounds, end_v, v):
                return Violation(Conflict.BEHIND, v, end_s, -math.inf, self._required(Conflict.BEHIND, tail, end_s, v))
        return None

    def _braking_on(self, v: Vehicle, end_s: float, end_x: float, end_v: float) -> Violation | None:
        """A measured vehicle held ahead may still be braking when the manoeuvre's ramp ends: the closing speed on it
        rises until it stands, while the AV holds ``end_v``. AHEAD over that stretch (after it, nothing changes)."""
        if v.dynamics is None:
            return None
        stop_s = v.dynamics.speed_mps[0] / v.dynamics.change.brake_mps2
        if stop_s <= end_s:
            return None
        hold = Piece(end_s, stop_s, end_x, end_v, 0.0)
        need = self._own_need(Conflict.AHEAD, v.dynamics, hold)
        return self._violation(Conflict.AHEAD, v, hold, need, True) if v.lo_m < need[0] + EPS_M else None

    def goal_holds(self, state: SoundState, goal: GoalRule) -> bool:
        """Every field of ``goal`` for every position of the vehicles it names (sensed ones, never phantoms)."""
        if goal.av_lane is not None and state.lane is not goal.av_lane:
            return False
        t_s = state.t_units * self.unit_s
        x_m = self.boundary_m(state)
        ex, length = self.sound.tracking.position_m, self.sound.safety.vehicle_length_m
        if goal.targets_behind and any(self.same_high(self.sensed_same[i], t_s) > x_m - ex - length
                                       for i in self.targets):
            return False
        most_m = self.nearest_target_m(goal)
        if most_m is not None:
            if not self.targets:
                return False
            v = self.sensed_same[self.targets[0]]
            gap_low = self.same_low(v, t_s) - (x_m + ex) - length
            gap_high = self.same_high(v, t_s) - (x_m - ex) - length
            if gap_low < 0 or gap_high > most_m:
                return False
        return not (goal.oncoming_passed and any(
            not self.passed(v, x_m, t_s) for v in self.oncoming if v.index is not None))

    def beyond_reach(self, state: SoundState, goal: GoalRule, actions_left: int) -> bool:
        """Whether ``goal`` cannot hold within ``actions_left`` more actions after ``state`` (guards and safety
        ignored): a target it leaves behind, or the nearest target it must come near, is farther ahead of the AV's
        reference than the AV can gain on its fastest position in that many actions (``gain_per_action_m`` each,
        plus what the first ramp can still add).

        Sound for a search bounded by the horizon only: a search that proves "no plan of any length" counts such a
        state as cut by the horizon, never as refused (``oracle.sound.shortest``)."""
        if not self.targets or not (goal.targets_behind or goal.nearest_target_m is not None):
            return False
        t_s = state.t_units * self.unit_s
        x_m = self.boundary_m(state)
        ramp = self.most_first_ramp_m if state.first_mps is None else self.first_ramp_m[state.first_mps]
        most = max(0.0, self.gain_per_action_m) * actions_left + ramp
        ex, length = self.sound.tracking.position_m, self.sound.safety.vehicle_length_m
        if goal.targets_behind and any(self.least_high(self.sensed_same[i], t_s) + length + ex - x_m > most + EPS_M
                                       for i in self.targets):
            return True  # a target's fastest position still ahead of where it must be behind the AV
        nearest = self.sensed_same[self.targets[0]]
        most_m = self.nearest_target_m(goal)
        return most_m is not None and self.least_high(nearest, t_s) - (x_m - ex) - length - most_m > most + EPS_M

    def hopeless(self, state: SoundState, goal: GoalRule) -> bool:
        """Whether ``goal`` can hold neither in ``state`` nor in any state after it, so a search need not go on.

        Two arguments, each sound under the model's own rules:

        - the nearest target's interval is already wider than the goal's gap allows (it only grows), or its far
          end already too far behind the phantom ahead (the AV must stay behind the phantom, and only gets more
          room when the target is slower than the phantom may be);
        - a target must still be passed, and it cannot be while the right lane is open. It must be passed
          from the right lane: the AV is in it, or the target is held ahead of an AV in the left lane (the
          AHEAD checks keep it there). Even at the fastest action's speed the AV is past the target (by the
          least cut-in gap) only at ``t_pass``; an oncoming phantom (the unseen stretch beyond the range)
          makes the right lane unusable from the time its nearest end is nearer than the least oncoming
          gap, and that time only comes sooner the farther the AV is. Positions at a boundary are taken
          with the most a ramp centred on it may add or take (``dip_m``)."""
        t_s = state.t_units * self.unit_s
        ex, length = self.sound.tracking.position_m, self.sound.safety.vehicle_length_m
        most_m = self.nearest_target_m(goal)
        if most_m is not None and self.targets:
            v = self.sensed_same[self.targets[0]]
            if self.least_high(v, t_s) - self.same_low(v, t_s) + 2 * ex > most_m + EPS_M:
                return True
            # A plan ends in the left lane (the right one is never safe for ever with phantoms), where the phantom
            # ahead is held ahead by at least the least gap: the AV cannot be near enough the target's far end.
            room = most_m - self.sound.safety.min_gap_m - 2 * ex
            if self.least_high_mps(v, t_s) >= self.sound.bounds.same_mps.low_mps and any(
                    self.least_high(v, t_s) - self.same_low(p, t_s) > room + EPS_M for p in self.same_phantoms_ahead):
                return True  # (a measured target's fastest speed only rises: no slower than the phantom from now on)
        if not (goal.targets_behind and self.targets and self.oncoming_phantoms):
            return False
        x_m = self.boundary_m(state)
        b, g_min = self.sound.bounds, self.sound.safety.min_gap_m
        least_m, nearest, fastest = self.least_oncoming_gap_m, self.nearest_phantom_m, self.fastest_mps
        followers = self.followers(state, None) if state.lane is Lane.LEFT else frozenset()
        for i in self.targets:
            v = self.sensed_same[i]
            if state.lane is Lane.LEFT and (self.same.index(v) in followers or
                                            not self.held_ahead(v, x_m + self.dip_m, t_s)):
                continue  # the left lane's rules may let it fall behind there: no argument
            if self.least_high(v, t_s) + length + g_min + ex <= x_m - self.dip_m - ex:
                continue  # already passed
            # the AV gains on the target's fastest position at most this fast from now on (a measured one's fastest
            # speed only rises from what it may be now)
            speed_gain = fastest - self.least_high_mps(v, t_s)
            if speed_gain <= 0:
                return True  # never passed for every position
            passed_at = t_s + max(0.0, (self.least_high(v, t_s) + length + g_min + 2 * ex - x_m - self.dip_m)
                                  / speed_gain)
            av_at = self.least_high(v, passed_at) + length + g_min + ex  # the AV's reference there, at least
            if nearest - b.oncoming_mps.high_mps * passed_at - (av_at + ex) - length < least_m - EPS_M:
                return True
        return False


def window_start_s(ref: Reference) -> float:
    """When a window from ``ref`` starts: at its boundary, or where the ramp into its action starts before it."""
    return min([ref.boundary_s] + ([ref.ramp.start_s] if ref.ramp is not None else []))


def early(ref: Reference) -> bool:
    """Whether the ramp into the first action still runs when a window from ``ref`` starts (its shape then depends
    on where the plan started, not only on the speed before it: computed as it is, never moved)."""
    first = ref.first
    return first is not None and first.start_s + first.duration_s > window_start_s(ref)


def _max_of(p: Piece, c1: float, b1: float, c2: float, b2: float, flip: bool = False) -> tuple[float, float]:
    """The largest value over ``p`` of the larger of two quadratics in ``s = t - t0`` with the piece's curvature
    (``+-acc/2 s^2 + b s + c``; ``flip``: the curvature negated, for a negated function), and the time it is reached."""
    a = (-p.acc_mps2 if flip else p.acc_mps2) / 2
    return max(_quad_max(a, b1, c1, p.span_s, p.t0_s), _quad_max(a, b2, c2, p.span_s, p.t0_s))


def _quad_max(a: float, b: float, c: float, span: float, t0: float) -> tuple[float, float]:
    """The maximum of ``a s^2 + b s + c`` over ``s`` in ``[0, span]`` and the time ``t0 + s`` it is reached at."""
    best = max((c, t0), (a * span * span + b * span + c, t0 + span))
    if a < 0:
        s = -b / (2 * a)
        if 0 < s < span:
            best = max(best, (a * s * s + b * s + c, t0 + s))
    return best
