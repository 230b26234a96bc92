"""What the sound model assumes of the world, stated: each lane's speed interval, the sensing error, and phantoms
where the sensors cannot see. Every number of a named profile says where it comes from.

A safety claim of the sound model holds for every motion inside these bounds (``oracle.reach``
checks it); outside them an event is an assumption violation, counted as such. Same-direction
speeds are along the AV's direction; oncoming speeds are magnitudes towards the AV. The sensing
error widens every sensed position by that much either way, on top of the cell it was put in
(a cell means anywhere within it, ``spec.cells``). A phantom is a vehicle assumed at the edge of
a sensor's view in each lane (its range; in the oncoming lane, nearer where a left-lane vehicle
hides the lane), moving within that lane's bounds, so that a vehicle arriving from beyond what the
sensors see is inside the assumptions. Nothing touches the AV at a snapshot (a vehicle that does has
already collided with it, an event of its own), so a vehicle in the AV's lane that cannot be clear
ahead of it is behind it (where followers react, that makes it a follower: ``spec.sound.follower_limit_m``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from spec.errors import OptionError, check_number
from spec.grid import WINDOW_M
from spec.lanes import Lane
from spec.physical import NOISE, SENSORS, SPEEDS, TRAFFIC


@dataclass(frozen=True, slots=True)
class SpeedBounds:
    """A closed interval of speeds, m/s."""

    low_mps: float
    high_mps: float


@dataclass(frozen=True, slots=True)
class Phantom:
    """A vehicle assumed where a sensor's range ends: in ``lane``, ``dx_m`` ahead of the AV (negative: behind)."""

    lane: Lane
    dx_m: float
    why: str

    @property
    def stretch_m(self) -> tuple[float, float]:
        """Where the phantom's vehicle may be: the whole unseen stretch, from ``dx_m`` outwards (every engine's
        interval for it)."""
        return (self.dx_m, math.inf) if self.dx_m > 0 else (-math.inf, self.dx_m)


@dataclass(frozen=True, slots=True)
class Bounds:
    """The sound model's assumptions: speeds per lane, sensing error, phantoms; ``source`` says where they come from."""

    name: str = field(compare=False)  # two bounds with the same numbers are the same assumptions
    same_mps: SpeedBounds
    oncoming_mps: SpeedBounds
    sensing_error_m: float
    phantoms: bool
    source: str = field(compare=False)
    #: whether a same-direction vehicle behind the AV brakes for it (False: it keeps its speed whatever the AV does,
    #: and the AV must not drive slower than it may while it is near: ``spec.safety.Conflict.BEHIND``)
    followers_react: bool = True
    #: how long the snapshot ages before the plan acts, seconds: the planner's time (``spec.physical.LOOP``'s
    #: ``plan_budget_s``, one control step, in the closed loop; 0 for a plan that acts at the snapshot's instant). The
    #: world moves on meanwhile and the AV keeps its reference speed; ``spec.sound.Sound.age_m`` turns it into metres.
    latency_s: float = 0.0

    def speeds(self, lane: Lane) -> SpeedBounds:
        """The bounds of the vehicles of ``lane`` (the left lane carries same-direction traffic, the right oncoming)."""
        return self.same_mps if lane is Lane.LEFT else self.oncoming_mps

    def phantom_vehicles(self, oncoming_view_m: float | None = None) -> tuple[Phantom, ...]:
        """The phantoms: a same-direction vehicle at each end of the left-lane sensor's range, an oncoming one where
        the front-right sensor's view of the oncoming lane ends: its range (``spec.physical.SENSORS``), or nearer,
        ``oncoming_view_m``, where a left-lane vehicle hides the lane from there on (a snapshot's,
        ``spec.sound.Sound.oncoming_view_m``). None when the profile has no phantoms."""
        if not self.phantoms:
            return ()
        oncoming = (Phantom(Lane.RIGHT, SENSORS.right_range_m, "front-right sensor's range")
                    if oncoming_view_m is None or oncoming_view_m >= SENSORS.right_range_m else
                    Phantom(Lane.RIGHT, oncoming_view_m, "front-right sensor's view, hidden by a left-lane vehicle"))
        return (Phantom(Lane.LEFT, SENSORS.left_range_m, "left-lane sensor's range, ahead"),
                Phantom(Lane.LEFT, -SENSORS.left_range_m, "left-lane sensor's range, behind"), oncoming)


def check_bounds(bounds: Bounds, key: Callable[[str], str] = lambda name: f"--{name.replace('_', '-')}") -> Bounds:
    """``bounds`` if every number is usable; else bad input naming the option (or file key: ``key`` of the field's
    name), the value and why."""
    for name, interval in (("same_mps", bounds.same_mps), ("oncoming_mps", bounds.oncoming_mps)):
        for end in (interval.low_mps, interval.high_mps):
            check_number(key(name), end)  # finite, at least 0: speeds are along the lane's direction
        if interval.low_mps > interval.high_mps:
            raise OptionError(key(name), f"{interval.low_mps:g}..{interval.high_mps:g}",
                              "the lower end is above the upper end")
    error = check_number(key("sensing_error_m"), bounds.sensing_error_m)
    if error > float(WINDOW_M):
        raise OptionError(key("sensing_error_m"), error, f"larger than the sensed window ({float(WINDOW_M):g} m)")
    check_number(key("latency_s"), bounds.latency_s, high=MAX_LATENCY_S)
    return bounds


#: The longest planning latency the bounds take, seconds: 15 control steps, far above the closed loop's budget (one). A
#: snapshot that old is no longer one to plan from: under the default bounds an oncoming vehicle closes near half a
#: paper cell on an AV at the common speed meanwhile (``spec.sound.Sound.age_m``: 9.55 m).
MAX_LATENCY_S = 0.5


_COMMON_MPS = TRAFFIC.speed_mps
_SPREAD = SpeedBounds(SPEEDS.mean_mps - SPEEDS.cut_sd * SPEEDS.sd_mps, SPEEDS.mean_mps + SPEEDS.cut_sd * SPEEDS.sd_mps)
#: How many standard deviations of the noisy sensor's range noise the default sensing error covers.
SENSING_SDS = 3.0

PROFILES: dict[str, Bounds] = {b.name: check_bounds(b) for b in (
    Bounds("paper", SpeedBounds(_COMMON_MPS, _COMMON_MPS), SpeedBounds(_COMMON_MPS, _COMMON_MPS), 0.0, True,
           "the paper's world: every vehicle at the common speed (spec.physical.TRAFFIC.speed_mps), sensing exact "
           "(a cell still means anywhere within it), phantoms at the sensors' ranges (traffic enters from beyond); "
           "followers keep their speed whatever the AV does (the paper's traffic never brakes)", False),
    Bounds("default", _SPREAD, _SPREAD, SENSING_SDS * NOISE.range_sd_m, True,
           f"speeds: the spread traffic's distribution (spec.physical.SPEEDS) cut where it is cut, mean +- "
           f"{SPEEDS.cut_sd:g} sd = {_SPREAD.low_mps:g}..{_SPREAD.high_mps:g} m/s, both lanes; sensing error: "
           f"{SENSING_SDS:g} x the noisy sensor's range sd (spec.physical.NOISE) = "
           f"{SENSING_SDS * NOISE.range_sd_m:g} m; phantoms at the sensors' ranges"),
)}
DEFAULT_PROFILE = "default"

#: The rule that gives a traffic model's lanes their speed bounds, written once per model (``world_bounds``): the
#: speeds the model's own law keeps a vehicle at, its stated events (stops, wrecks) left out. ``paper``: every
#: vehicle at the common speed; ``spread`` and ``following``: the desired-speed distribution where it is cut (a
#: spread vehicle keeps its own speed or its slower leader's; an IDM vehicle converges to its desired speed or its
#: leader's and never drives above its desired speed). A following vehicle braking below the cut (behind a stop,
#: a wreck, a slow AV, or closing on a leader spawned near it) is outside: an assumption violation, counted.
TRAFFIC_SPEEDS: dict[str, tuple[SpeedBounds, str]] = {
    "paper": (SpeedBounds(_COMMON_MPS, _COMMON_MPS), "every vehicle at the common speed (spec.physical.TRAFFIC)"),
    "spread": (_SPREAD, f"the desired speeds' cut (spec.physical.SPEEDS), mean +- {SPEEDS.cut_sd:g} sd"),
    "following": (_SPREAD, f"the desired speeds' cut (spec.physical.SPEEDS), mean +- {SPEEDS.cut_sd:g} sd; IDM "
                           "braking below it (stops, wrecks, a slow leader) is outside"),
}
#: Whether a traffic model's followers react to the AV, from the model's own law (``Bounds.followers_react``).
TRAFFIC_FOLLOWERS_REACT: dict[str, tuple[bool, str]] = {
    "paper": (False, "followers keep the common speed whatever the AV does (the paper's traffic never brakes)"),
    "spread": (True, "a follower takes its leader's speed, the AV's included, at the minimum gap"),
    "following": (True, "a follower brakes by the IDM behind its leader, the AV included"),
}
#: The rule for each sensing model's error: ``exact`` none (a cell still means anywhere within it); ``noisy``
#: ``SENSING_SDS`` times its range noise's sd. Missed readings are not bounded: a vehicle the plan did not know that
#: turns up where its safety depends on is an assumption violation.
SENSING_RULES: dict[str, str] = {"exact": "exact sensing: no error",
                                 "noisy": f"{SENSING_SDS:g} x the noisy sensor's range sd"}


def speed_error_mps(sensing: str, range_rate_sd_mps: float = NOISE.range_rate_sd_mps) -> float:
    """The error bound of a sensing model's range-rate readings (the tracker's speed intervals, ``spec.tracking``), by
    the range's rule (``SENSING_RULES``): none when exact, ``SENSING_SDS`` times the rate noise's sd when noisy."""
    if sensing not in SENSING_RULES:
        raise OptionError("--sensor", sensing,
                          f"no error rule for this sensing model (known: {', '.join(SENSING_RULES)})")
    return SENSING_SDS * check_number("range_rate_sd_mps", range_rate_sd_mps) if sensing == "noisy" else 0.0


def world_bounds(traffic: str, sensing: str, range_sd_m: float = NOISE.range_sd_m, scale: float = 1.0) -> Bounds:
    """The planner's bounds for a world of ``traffic`` and ``sensing`` (``TRAFFIC_SPEEDS``, ``SENSING_RULES``), phantoms
    on; ``scale`` multiplies each speed interval's half-width about its middle (never below a standstill) and the
    sensing error: the bound-width sweep's one knob, 1 for the rule's own bounds."""
    if traffic not in TRAFFIC_SPEEDS:
        raise OptionError("--traffic", traffic, f"no bounds rule for this traffic model (known: "
                          f"{', '.join(TRAFFIC_SPEEDS)})")
    if sensing not in SENSING_RULES:
        raise OptionError("--sensor", sensing, f"no bounds rule for this sensing model (known: "
                          f"{', '.join(SENSING_RULES)})")
    scale = check_number("--bounds-scale", scale)
    speeds, why = TRAFFIC_SPEEDS[traffic]
    react, react_why = TRAFFIC_FOLLOWERS_REACT[traffic]
    middle, half = (speeds.low_mps + speeds.high_mps) / 2, (speeds.high_mps - speeds.low_mps) / 2
    scaled = SpeedBounds(max(0.0, middle - scale * half), middle + scale * half)
    error = scale * (SENSING_SDS * check_number("--range-sd-m", range_sd_m) if sensing == "noisy" else 0.0)
    name = f"{traffic}+{sensing}" + ("" if scale == 1 else f" x{scale:g}")
    source = (f"traffic {traffic}: {why} = {scaled.low_mps:g}..{scaled.high_mps:g} m/s, both lanes; {react_why}; "
              f"sensing {sensing}: {SENSING_RULES[sensing]} = {error:g} m; phantoms at the sensors' ranges"
              + ("" if scale == 1 else f"; widths x {scale:g} (--bounds-scale)"))
    return check_bounds(Bounds(name, scaled, scaled, error, True, source, react))


def profile(name: str, where: str = "--bounds") -> Bounds:
    """The named profile; an unknown name is bad input listing the known ones."""
    found = PROFILES.get(name)
    if found is None:
        raise OptionError(where, name, f"unknown bounds profile (known: {', '.join(PROFILES)})")
    return found


def parse_speeds(text: object, where: str) -> SpeedBounds:
    """A speed interval as options and files write it: ``"LO..HI"`` (a single number: that speed exactly), or a
    two-number list from a file; bad input names ``where``."""
    if isinstance(text, (list, tuple)):
        if len(text) != 2:
            raise OptionError(where, text, "must be two speeds [low, high] in m/s")
        low, high = text
    else:
        parts = str(text).split("..")
        if len(parts) > 2 or not all(p.strip() for p in parts):
            raise OptionError(where, text, "must be LOW..HIGH in m/s (or one speed)")
        low, high = parts[0], parts[-1]
    ends = []
    for end in (low, high):
        if isinstance(end, bool):
            raise OptionError(where, text, "a speed must be a number of m/s")
        try:
            ends.append(float(end) if isinstance(end, str) else end)
        except ValueError:
            raise OptionError(where, text, "a speed must be a number of m/s") from None
    for end in ends:
        check_number(where, end)
    bounds = SpeedBounds(float(ends[0]), float(ends[1]))
    if bounds.low_mps > bounds.high_mps:
        raise OptionError(where, text, "the lower end is above the upper end")
    return bounds
