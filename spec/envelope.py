"""The AV's envelope: where the AV can be, and how fast, at every instant of a plan of the sound model.

The AV follows the executor's speed reference (``spec.motion``: a ramp from its measured speed into
the first action, starting at once; between two actions a ramp centred on their boundary), and the
car stays within ``Tracking`` of it: its position within ``position_m`` of the reference's integral,
its speed within ``speed_mps`` of the reference. A lane change's sideways move takes at most
``lateral_s``; during it the AV occupies both lanes. After a plan, the stated minimal-risk
manoeuvre (``MinimalRisk``) keeps the AV safe for ever under the bounds, or the plan is refused.

``Reference`` is the reference from one decision boundary on, which is all a step needs: the
plan's start (its first ramp may still run), the nominal position at the boundary (the paper's
instant speed changes), the speed before it, and the one ramp centred on (or, for the
minimal-risk manoeuvre, starting at) the boundary. Centred ramps of neighbouring boundaries never
overlap for the declared actions (a test holds every triple of actions to it), so no other ramp
runs inside a step's window.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from spec.actions import ACTION_RULES
from spec.grid import COMMON_SPEED_MPS
from spec.motion import RAMP_SHARE, Ramp, covered_s, ramp_s
from spec.physical import CAR, LOOP, NOISE, SENSORS
from spec.safety import SAFETY


@dataclass(frozen=True, slots=True)
class Tracking:
    """How closely the car follows its reference (the executor's stated tracking error) and how long a sideways
    move may take; ``source`` says where the numbers come from."""

    position_m: float
    speed_mps: float
    lateral_s: float
    source: str = field(compare=False)


#: The executor's envelope, measured (``docs/sound.md``, "The AV's envelope"). Rule: the largest deviation over
#: 10 x 25 km of paper and 10 x 25 km of spread traffic (exact sensing, seeds 1-10), leaving out the 4 s start-up
#: from standstill, contact instants and plans whose reference starts ahead of the car (frame fallbacks: the sound
#: model's plans start their reference at the car), rounded up to 0.5: measured 1.27 m and 1.19 m/s (2026-11-25).
#: Measured again 2026-12-07 with the sound model's plans starting on the proved reference the car runs on
#: (``python -m ci.bench.envelope``: paper, spread and following traffic, 10 x 25 km each): 1.23 m and 1.32 m/s.
#: The sideways move: the executor is told to make it within ``LOOP.lane_change_lateral_s``; the car's body was
#: measured clear of the old lane within 1.87 s.
TRACKING = Tracking(1.5, 1.5, LOOP.lane_change_lateral_s,
                    "executor measured 2026-11-25: max |x - x_ref| 1.27 m, |v - v_ref| 1.19 m/s over 2 x 250 km "
                    "(paper, spread; start-up, contacts and frame fallbacks left out), rounded up to 0.5; sideways "
                    "move LOOP.lane_change_lateral_s = 2 s (body clear of the old lane within 1.87 s measured)")
#: The car's lag behind a reference that brakes or speeds up, m/s: the 99.9th percentile of |v - v_ref| with the
#: reference restarted at the car at every plan, paper traffic, measured 2026-11-25 (0.64 in spread; CHANGELOG.md,
#: "the AV's envelope as measured on 2026-11-25"). What the envelope's speed error leaves above it bounds where a plan
#: may start on the reference rather than at the car (``sim.driver.decide.plan_start``).
SPEED_LAG_MPS = 0.87
#: No envelope at all: the AV exactly on its reference, lane changes instant (the paper's AV).
EXACT_AV = Tracking(0.0, 0.0, 0.0, "the paper's AV: exactly on its reference, lane changes instant")


#: A ramp's end speed is a sum of floats: one that ends at the hold speed (the slowest speed ahead) may come out a
#: rounding above it, which must not count as closing in (1e-9 m/s closes 1 mm in 11 days).
CLOSING_EPS_MPS = 1e-9


def closing_fit_sweeps(range_sd_m: float = NOISE.range_sd_m, sweep_hz: float = SENSORS.sweep_hz,
                       most_sd_mps: float = TRACKING.speed_mps) -> int:
    """How many consecutive sweeps the fallback fits the closing speed on the vehicle ahead over (a least-squares
    line through its distances): the fewest whose fitted speed's sd, from the noisy sensor's stated range noise, is
    at most the executor's stated speed error, so that the fallback knows the speed ahead as closely as the car holds
    its own. At 0.5 m and 10 Hz: 6 sweeps (0.5 s), an sd of 1.2 m/s; two readings' difference has 7.1 m/s, and
    was measured jumping by -12 .. +14 m/s between sweeps. A longer window lags a braking vehicle by more (half the
    window's span times its deceleration)."""
    sweeps = 2
    while range_sd_m * sweep_hz / math.sqrt(sweeps * (sweeps * sweeps - 1) / 12) > most_sd_mps:
        sweeps += 1
    return sweeps


def fitted_closing_mps(distances_m: tuple[float, ...], sweep_hz: float = SENSORS.sweep_hz) -> float | None:
    """The closing speed on a vehicle from its distances at consecutive sweeps (oldest first): minus the slope of
    their least-squares line; None from fewer than three (two readings' difference is all noise: see
    ``closing_fit_sweeps``)."""
    n = len(distances_m)
    if n < 3:
        return None
    mean_i, mean_d = (n - 1) / 2, sum(distances_m) / n
    slope = sum((i - mean_i) * (d - mean_d) for i, d in enumerate(distances_m)) / (n * (n * n - 1) / 12)
    return -slope * sweep_hz


def own_motion_closing_mps(distances_m: tuple[float, ...], travelled_m: tuple[float, ...], av_mps: float,
                           behind: bool = False, sweep_hz: float = SENSORS.sweep_hz) -> float | None:
    """The closing speed on a vehicle at the last sweep, the AV's own motion taken out of the fit: the vehicle's own
    speed is fitted (``fitted_closing_mps``) through where it was along the road (each distance moved by the AV's
    travel from that sweep to the last, ``travelled_m``, its odometer at each sweep), and the closing speed is the
    AV's speed then (``av_mps``) against it. A fit of the distances alone gives the closing speed at the middle of
    its window: while the AV speeds up, half the window's span times its acceleration too low (measured: seed 48
    of the reliability campaign at c2c5ab8 returned from the oncoming lane at 9.8 m/s behind a vehicle at 7.0 m/s,
    the fit saying 2.2 m/s closing, not 2.8, and came within 0.6 m of it). ``behind``: a vehicle behind the AV
    (its distance grows as the AV moves on); None from fewer than three sweeps."""
    sign = -1.0 if behind else 1.0
    last = travelled_m[-1] if travelled_m else 0.0
    fitted = fitted_closing_mps(tuple(d + sign * (a - last) for d, a in zip(distances_m, travelled_m, strict=True)),
                                sweep_hz)
    return None if fitted is None else fitted + sign * av_mps


@dataclass(frozen=True, slots=True)
class MinimalRisk:
    """The minimal-risk manoeuvre after a plan (and the fallback's): stay in lane and brake, at the share of the car's
    braking limit the executor's ramps use, down to a hold speed no vehicle ahead can be slower than.

    The fallback (the simplex pattern; RSS's proper response) takes over in the closed loop when a decision from a
    fresh snapshot has neither a plan nor a safe step in lane (``oracle.sound.keep_lane``), when the snapshot makes
    no scenario, or when a vehicle that broke the assumptions under one decision breaks them again under the next.
    Its rules (``sim.driver.fallback`` applies them; the drives that made each one are in CHANGELOG.md):

    - **In the right lane, wait for room, then return.** Room: nothing alongside within ``beside_m``; the vehicle
      ahead not nearer than the specification allows at its closing speed once the lane change is over, the car's
      envelope taken (``too_near_after``); where followers keep their speed, the vehicle behind neither nearer than
      that nor faster than the AV by more than ``open_mps``.
    - **While it waits**, it drives at the left lane's speed: the vehicle ahead's while that one is too near;
      beside a vehicle (its centre ahead of the AV's) ``open_mps`` below it, unless the AV is the faster and
      passing ends sooner (``pass_s`` against ``drop_back_s``), then at least ``open_mps`` above it; beside a
      vehicle alongside behind, ``open_mps`` above it when the AV is the faster or passing ends sooner and the
      left lane has a slot ahead of it (``leaves_slot``), else ``open_mps`` below it; passing, only a gap ahead
      that breaks the specification now holds it back; a too-near or faster follower's own speed where followers
      keep theirs. Never a standstill beside a vehicle faster than ``open_mps``.
    - **The wait ends** (``ends_wait``) when the sensed left lane leaves room, when the nearest oncoming vehicle
      sensed would be nearer than the specification allows after one more sweep and the lane change (before its
      speed is fitted: the AV's speed plus the bounds' fastest oncoming speed), after ``takeover_s`` when sweeps
      are dropped, and after ``return_wait_s`` whatever it sees: the oncoming lane is the greater danger. Beside a
      left-lane vehicle (centres within ``beside_m``), the oncoming vehicle ends it only once it would come within
      the least gap, no time gap (``apart_after``): moving over beside a vehicle makes a side collision certain, and
      the wait drops back or passes meanwhile.
    - **The return** runs at the speed it starts at, unless it would end nearer the vehicle ahead than the
      specification allows (only a return the oncoming lane forces): then it brakes at ``emergency_decel_mps2`` to
      that vehicle's fitted speed (not fitted yet: the slowest the bounds let it be), from its start or once clear
      of a vehicle it is passing (``sim.driver.nearest.pass_first_s``). Once its sideways move is over it ends at
      once where the vehicle ahead is nearer than the specification allows at the closing speed measured then, and
      the brake in lane takes over (a vehicle that brakes harder than at the return's start, to a standstill, closes
      faster than the profile was chosen for: ``sim.driver.fallback.too_near_now``).
    - **In lane**, it brakes at ``decel_mps2`` to the hold speed (``fallback_hold_mps``) and, while the sensed
      vehicle ahead is nearer than the specification allows at the closing speed (``fallback_closing_mps``), at
      ``emergency_decel_mps2`` down to that vehicle's speed (a standstill when it is not known), never up (the
      speed of a vehicle that does not close, above the command the car runs over, keeps the gap as near), and on
      below it while the measured gap still closes (the car may run above its command). Where the gap ahead is
      within the specification but a decision from the last sweep would find no safe step in lane, and it is the
      smaller of the two gaps in the lane, it drives ``open_mps`` below the vehicle ahead while the vehicle behind
      stays farther than the specification allows at that closing speed, towards the middle of its slot.
    - It holds for ``takeover_s``, then hands back to a new decision (which may take over again).

    One rule acts before a take-over, when a breach (sensed, or of the AV's own envelope) ends a sound decision
    during a lane change's sideways move (the proof covers neither finishing the move nor undoing it once its sets
    are broken): **the move is cut short** and goes back to the lane it left, on a cosine of the time it had taken,
    when finishing it looks the worse of the two as sensed, within ``reverse_within_s`` of its start. Out into the
    right lane: when the oncoming lane would not leave time for the rest of the move and a return (the oncoming lane
    is the greater danger; a dropped sweep shows nothing of it). Back into the left lane: when that lane would break
    the specification at the move's end (a vehicle alongside, the vehicle ahead too near, a follower that blocks)
    and the oncoming lane leaves time to move back and return again. Nothing of the decision's proof is kept after
    it. Each one is counted (``reversed_moves``).
    """

    decel_mps2: float = RAMP_SHARE * CAR.max_brake_mps2
    emergency_decel_mps2: float = CAR.max_brake_mps2  # the car's own braking limit
    accel_mps2: float = RAMP_SHARE * CAR.max_accel_mps2  # the fallback back up to its hold speed
    takeover_s: float = LOOP.wait_s  # one take-over lasts as long as a wait without a plan
    #: How much slower than the vehicle ahead the fallback drives to open the gap a decision needs to hand back to:
    #: the executor's stated speed error (``TRACKING.speed_mps``), so that the gap opens whatever the car's speed
    #: error within its envelope (measured: 0.17 m/s above a command of 7 m/s held a 2 m gap for 35 km, seed 12).
    open_mps: float = TRACKING.speed_mps
    #: How long into a lane change's sideways move it may still be cut short: its first quarter, where the reference
    #: has moved 15% of a lane width. Measured (``tests/sim/test_physics.py``, 3.5-14 m/s): going back from there the
    #: car is wholly in the lane it started in once the move back ends, and within 0.2 m of its centre 3 s later; from
    #: half-way, at 3.5 m/s, the car runs on into the other lane before it turns back.
    reverse_within_s: float = LOOP.lane_change_lateral_s / 4
    #: Sweeps the closing speed on the vehicle ahead is fitted over (``closing_fit_sweeps``).
    fit_sweeps: int = closing_fit_sweeps()
    #: The longest the fallback waits in the right lane for room, however clear the oncoming lane looks: the time an
    #: oncoming vehicle at the front-right sensor's range needs to reach the AV closing at twice the common speed
    #: (25.5 s); a bound, so that a left lane that never leaves room (a vehicle stopped beside the AV) cannot hold
    #: the drive for ever.
    return_wait_s: float = SENSORS.right_range_m / float(2 * COMMON_SPEED_MPS)
    #: Two vehicles in neighbouring lanes whose centres are nearer than this along the road are beside each other:
    #: a car length and the specification's least gap (the gap either would have to the other in one lane).
    beside_m: float = CAR.length_m + SAFETY.min_gap_m

    @property
    def reaction_s(self) -> float:
        """How late the fallback's emergency brake may act after the gap ahead first breaks the specification: the
        gap is read once per sweep, and the brake is commanded at the next control step."""
        return 1.0 / SENSORS.sweep_hz + LOOP.control_dt_s

    def emergency_cancels_mps(self) -> float:
        """The highest closing speed on a vehicle that keeps its speed (or stands) that the emergency brake cancels
        before contact, braking at ``emergency_decel_mps2`` from ``reaction_s`` after the gap first breaks the
        specification: the gap then, ``time_gap_s x v`` less the ``v x reaction_s`` closed meanwhile, must exceed
        the ``v^2 / (2 x emergency_decel_mps2)`` that braking closes, so ``v < 2 x emergency_decel_mps2 x (time_gap_s
        - reaction_s)`` (16.4 m/s at 6 m/s^2; below ``min_gap_m / time_gap_s`` the trigger gap is the least gap,
        larger still). A vehicle ahead that brakes after the trigger is outside this bound (it broke the bounds)."""
        return 2.0 * self.emergency_decel_mps2 * (SAFETY.time_gap_s - self.reaction_s)

    @staticmethod
    def fastest_closing_mps() -> float:
        """The fastest the AV may close on a standing vehicle: its fastest action's speed and the executor's stated
        speed error (``TRACKING``), the speed the emergency brake must be able to cancel."""
        fastest = max(rule.speed_factor for rule in ACTION_RULES.values())
        return float(fastest) * COMMON_SPEED_MPS + TRACKING.speed_mps

    def leaves_slot(self, apart_m: float) -> bool:
        """Whether two vehicles in one lane whose centres are ``apart_m`` apart leave a slot for the AV between them:
        ``beside_m`` from its centre to either one's (a car length and the least gap each side)."""
        return apart_m >= 2.0 * self.beside_m

    def ends_wait(self, waited_s: float, swept: bool, oncoming_leaves_time: bool) -> bool:
        """Whether the fallback's wait in the right lane ends now, with or without room in the left lane: after
        ``return_wait_s``; or once the oncoming lane leaves no time, from the wait's start when the last sweep was
        read (``swept``), only after ``takeover_s`` when it was dropped (it shows nothing)."""
        return waited_s > self.return_wait_s or (
            (swept or waited_s > self.takeover_s) and not oncoming_leaves_time)

    def pass_s(self, closing_mps: float, ahead_m: float) -> float:
        """How long the fallback waiting in the right lane takes to pass a left-lane vehicle whose centre is
        ``ahead_m`` ahead of its own (negative: behind it), closing on it at ``closing_mps`` (negative: the vehicle
        the faster): speeding up at ``accel_mps2`` until it is ``open_mps`` the faster (its speed when it already is),
        then keeping that, until the AV's centre is ``beside_m`` ahead of the vehicle's. Whether there is room ahead
        of the vehicle is the caller's to know."""
        return covered_s(ahead_m + self.beside_m, closing_mps, max(closing_mps, self.open_mps), self.accel_mps2)

    def drop_back_s(self, closing_mps: float, ahead_m: float, own_mps: float) -> float:
        """How long the fallback waiting in the right lane takes to drop back behind a left-lane vehicle whose centre
        is ``ahead_m`` ahead of its own (negative: behind it), closing on it at ``closing_mps``, at ``own_mps``: its
        speed moving to ``open_mps`` below the vehicle's (a standstill at the least), braking at
        ``emergency_decel_mps2`` (the wait's rate) or speeding up at ``accel_mps2``, then keeping that, until the
        vehicle's centre is ``beside_m`` ahead of the AV's (infinite when the vehicle stands: the AV cannot open on
        it)."""
        opening_mps = min(self.open_mps, max(0.0, own_mps))
        if opening_mps <= 0.0:
            return math.inf
        rate = self.emergency_decel_mps2 if opening_mps > -closing_mps else self.accel_mps2
        return covered_s(self.beside_m - ahead_m, -closing_mps, opening_mps, rate)

    def hold_mps(self, speed_mps: float, slowest_ahead_mps: float) -> float:
        """The speed the manoeuvre brakes to: at most the slowest speed a vehicle ahead may keep (so the reference
        never closes in on it), never below a standstill, never faster than the AV already is.

        The car's speed error is not taken off: the envelope (``Tracking``) holds the car within ``position_m`` of
        the reference's integral at every instant, so a reference at the leader's slowest speed keeps every gap
        ahead within ``position_m`` of where it was, for ever; the specification's check of each instant already
        takes that position error and the speed error's closing. Taking the speed error off as well made the AV
        brake below the speed of traffic that keeps its speed exactly (the paper's), whose followers do not react."""
        return max(0.0, min(speed_mps, slowest_ahead_mps))

    def fallback_hold_mps(self, slowest_ahead_mps: float) -> float:
        """The speed the fallback holds in lane once nothing ahead is too near: the slowest speed ahead the world's
        bounds give, from below as from above (a slow AV comes back up to it at ``accel_mps2``). A plan's own
        manoeuvre never speeds up (its proof is of braking); the fallback acts where that proof no longer holds, and
        an AV left slower than traffic whose followers do not brake is run into (measured: seed 6 of the faults
        evaluation, rear-ended at 6.2 m/s after two take-overs)."""
        return max(0.0, slowest_ahead_mps)

    @staticmethod
    def fallback_closing_mps(speed_mps: float, measured_mps: float | None) -> float:
        """The closing speed on the sensed vehicle ahead the fallback brakes for: the one fitted over the last sweeps
        (``fitted_closing_mps`` over ``fit_sweeps``), kept within ``[0, speed_mps]``; not measured (its first two
        sweeps, or the nearest vehicle changed), the AV's whole speed: it may stand. The bounds no longer hold when
        the fallback acts, so it assumes none; braking for a standstill that is not there, where followers do not
        brake, was what ran the AV into them (measured: every one of the sound model's collisions with faults and
        tracking, seeds 1-7, happened during the fallback)."""
        if measured_mps is None:
            return max(0.0, speed_mps)
        return min(max(0.0, measured_mps), max(0.0, speed_mps))

    @staticmethod
    def apart_after(gap_m: float, closing_mps: float, seconds: float, tracking: Tracking = TRACKING) -> bool:
        """Whether a gap of ``gap_m`` (bumper to bumper), closing at ``closing_mps`` for ``seconds`` of the AV's
        reference, is then still the specification's least gap (``SafetySpec.min_gap_m``), the car's envelope taken:
        the weaker test of ``too_near_after``, without the time gap."""
        return gap_m - closing_mps * seconds - tracking.position_m >= SAFETY.min_gap_m

    @staticmethod
    def too_near_after(gap_m: float, closing_mps: float, seconds: float, tracking: Tracking = TRACKING) -> bool:
        """Whether a gap of ``gap_m`` (bumper to bumper), closing at ``closing_mps`` for ``seconds`` of the AV's
        reference, is then nearer than the safety specification allows at that closing speed. A prediction
        (``seconds`` above 0: the fallback's return, at the speed it starts at) takes the executor's stated envelope,
        as the planner's checks do: the car may end ``position_m`` nearer than its reference and close
        ``speed_mps`` faster. A gap measured now (0 s) is taken as it is. Measured without the envelope: seed 7 of
        the paper's world at 33fbde8 (km 21.8) returned behind a vehicle whose gap, 29.9 m closing at 6.6 m/s, was
        predicted 0.26 m more than the specification requires at the return's end; the car ran 0.6 m/s above its
        reference after the sideways move, and the return ended 0.1 m short of it, a near miss (gap 8.0 m at 1.39 s)."""
        if seconds <= 0.0:
            return SAFETY.violated(gap_m, closing_mps)
        return SAFETY.violated(gap_m - closing_mps * seconds - tracking.position_m, closing_mps + tracking.speed_mps)

    def handback_mps(self, speed_mps: float, hold_mps: float) -> float:
        """The speed the fallback asks a decision about when it decides whether to open the gap ahead: the AV's
        speed or the hold speed, whichever is higher, plus the executor's stated speed error (``TRACKING``): the car
        runs on above its command (0.17 m/s measured), and a gap opened only for the speed of the moment was closed
        again the moment it was handed back (measured: seed 12, the fallback braking and speeding up in turn)."""
        return max(speed_mps, hold_mps) + TRACKING.speed_mps

    def closes_in(self, end_mps: float, slowest_ahead_mps: float) -> bool:
        """Whether a reference that ends the manoeuvre at ``end_mps`` keeps closing in on a vehicle ahead that may
        drive at ``slowest_ahead_mps`` (then no such vehicle may be held ahead after it: it would be reached)."""
        return end_mps > slowest_ahead_mps + CLOSING_EPS_MPS

    def ramp(self, at_s: float, speed_mps: float, hold_mps: float) -> Ramp | None:
        """The braking ramp, starting at ``at_s`` (none when the AV already drives at the hold speed)."""
        if hold_mps >= speed_mps:
            return None
        return Ramp(at_s, (speed_mps - hold_mps) / self.decel_mps2, hold_mps - speed_mps)


MINIMAL_RISK = MinimalRisk()


@dataclass(frozen=True, slots=True)
class Piece:
    """The reference on ``[t0_s, t1_s]``: position ``x0_m + v0_mps s + acc_mps2 s^2 / 2``, speed ``v0_mps + acc_mps2
    s``, with ``s = t - t0_s`` (times on the plan's clock, positions from the AV's place at the plan's start)."""

    t0_s: float
    t1_s: float
    x0_m: float
    v0_mps: float
    acc_mps2: float

    @property
    def span_s(self) -> float:
        return self.t1_s - self.t0_s

    def x(self, t_s: float) -> float:
        s = t_s - self.t0_s
        return self.x0_m + self.v0_mps * s + self.acc_mps2 * s * s / 2

    def v(self, t_s: float) -> float:
        return self.v0_mps + self.acc_mps2 * (t_s - self.t0_s)


@dataclass(frozen=True, slots=True)
class Reference:
    """The speed reference from one decision boundary on (see the module's docstring)."""

    start_mps: float  # the car's measured speed at the plan's start
    first_mps: float  # the first action's speed
    boundary_s: float  # the boundary, on the plan's clock
    nominal_m: float  # where the paper's AV (instant speed changes, the first action from t = 0) is at it
    before_mps: float  # the nominal speed before the boundary (the first action's at the plan's start)
    ramp: Ramp | None  # the ramp at the boundary: centred on it, or the minimal-risk manoeuvre's from it

    @property
    def first(self) -> Ramp | None:
        """The ramp into the first action: from the measured speed, starting at once."""
        if self.first_mps == self.start_mps:
            return None
        return Ramp(0.0, ramp_s(self.start_mps, self.first_mps), self.first_mps - self.start_mps)

    def _ramps(self) -> tuple[Ramp, ...]:
        return tuple(r for r in (self.first, self.ramp) if r is not None)

    def position_m(self, t_s: float) -> float:
        """The reference's position at ``t_s`` (the nominal position plus what each ramp has gained on it)."""
        ramps = sum(r.integral_m(t_s) for r in self._ramps())
        return (self.start_mps - self.first_mps) * t_s + self.nominal_m + self.before_mps * (t_s - self.boundary_s) \
            + ramps

    def speed_mps(self, t_s: float) -> float:
        """The reference speed at ``t_s``."""
        return self.start_mps - self.first_mps + self.before_mps + sum(r.at(t_s) for r in self._ramps())

    def pieces(self, t0_s: float, t1_s: float) -> list[Piece]:
        """The reference on ``[t0_s, t1_s]`` cut where a ramp starts or ends: constant acceleration on each piece."""
        cuts = {t0_s, t1_s}
        for r in self._ramps():
            cuts.update(t for t in (r.start_s, r.start_s + r.duration_s) if t0_s < t < t1_s)
        times = sorted(cuts)
        out = []
        for a, b in zip(times, times[1:] or times):
            mid = (a + b) / 2
            acc = sum(r.dv_mps / r.duration_s for r in self._ramps()
                      if r.duration_s > 0 and r.start_s <= mid < r.start_s + r.duration_s)
            out.append(Piece(a, b, self.position_m(a), self.speed_mps(a), acc))
        return out
