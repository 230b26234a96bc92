"""The fallback's decisions (``spec.envelope.MinimalRisk``), as pure functions of what it sensed (``Around``) and the
car's speed: when to return from the right lane, how fast to drive while it waits, the return's speed reference,
and each control step's speed command while it brakes in lane. The sound model's driver executes what they return
(``sim.driver.takeover``, ``sim.driver.sound.SoundDriver.fallback``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from sim.driver.nearest import Nearest, drop_back_to, pass_first_s, room_ahead_of
from sim.driver.readings import Reading
from spec.actions import ACTION_RULES, Action
from spec.assumptions import Bounds
from spec.envelope import CLOSING_EPS_MPS, MINIMAL_RISK
from spec.lanes import Lane
from spec.motion import Ramp, SpeedProfile
from spec.physical import SENSORS
from spec.safety import SAFETY

#: How long the fallback's return to the left lane takes: the lane change's own duration.
RETURN_S = float(ACTION_RULES[Action.LEFT_LANE_CHANGE].duration_s)


@dataclass(frozen=True, slots=True)
class Around:
    """What the fallback knows at the last sweep: the nearest vehicles sensed ahead and behind in the left lane and
    ahead in the right one, whether that sweep arrived (a dropped sweep shows nothing), and the drive's stated
    bounds (None: none stated)."""

    lead: Nearest | None
    follower: Nearest | None
    oncoming: Nearest | None
    swept: bool
    bounds: Bounds | None


def alongside(readings: tuple[Reading, ...]) -> bool:
    """Whether a left-lane vehicle is beside the AV (its centre within ``MinimalRisk.beside_m`` behind the AV's, up
    to level with it): the right lane's wait holds while one is."""
    return any(r.lane is Lane.LEFT and -MINIMAL_RISK.beside_m < r.dx_m <= 0 for r in readings)


def follower_blocks(a: Around, speed_mps: float, change_s: float = RETURN_S) -> bool:
    """Where followers keep their speed (``Bounds.followers_react`` False), whether the vehicle sensed behind in the
    left lane would be nearer than the specification allows at its fitted closing speed once a return of
    ``change_s`` is over (not measured yet: it blocks, for the two sweeps a fit needs; closing faster than
    ``MinimalRisk.open_mps``: it blocks, the AV speeds up first)."""
    f = a.follower
    if f is None or a.bounds is None or a.bounds.followers_react:
        return False
    f_closing_mps = f.closing_now_mps(speed_mps)
    if f_closing_mps is None or f_closing_mps > MINIMAL_RISK.open_mps:
        return True
    return f.too_near_after(max(0.0, f_closing_mps), change_s)


def oncoming_leaves_time(a: Around, speed_mps: float, change_s: float = RETURN_S, gap_only: bool = False) -> bool:
    """Whether the fallback may wait one more sweep in the right lane: the nearest oncoming vehicle sensed would
    still be farther than the specification allows at its fitted closing speed after that sweep and a return of
    ``change_s`` (none sensed within the front-right sensor's range: yes, each sweep looks again; a dropped sweep:
    no; its speed not measured yet, for the sweeps a fit needs: ``speed_mps`` plus the fastest oncoming speed the
    drive's bounds state; no bounds stated: no). ``gap_only``: farther than the least gap alone, no time gap
    (``MinimalRisk.apart_after``), the wait beside a vehicle in the left lane (``alongside_now``)."""
    if not a.swept:
        return False
    o = a.oncoming
    if o is None:
        return True
    o_closing_mps = o.closing_now_mps(speed_mps)
    if o_closing_mps is not None:
        closing = max(0.0, o_closing_mps)
    elif a.bounds is not None:
        closing = speed_mps + a.bounds.oncoming_mps.high_mps
    else:
        return False
    seconds = change_s + 1 / SENSORS.sweep_hz
    if gap_only:
        return MINIMAL_RISK.apart_after(o.gap_m, closing, seconds)
    return not o.too_near_after(closing, seconds)


def alongside_now(a: Around, beside: bool) -> bool:
    """Whether a left-lane vehicle is beside the AV now: one alongside behind (``beside``, from ``alongside``) or the
    vehicle ahead with its centre less than ``MinimalRisk.beside_m`` ahead of the AV's."""
    return beside or (a.lead is not None and a.lead.dx_m < MINIMAL_RISK.beside_m)


def reverses(a: Around, readings: tuple[Reading, ...], speed_mps: float, to_lane: Lane, done_s: float,
             left_s: float) -> bool:
    """Whether a sideways move under way when a breach ends the decision goes back to the lane it left
    (``MinimalRisk``'s cut-short move; ``done_s`` of it done, ``left_s`` left). Out into the right lane: when the
    oncoming lane would not leave time for the rest of the move and a return (``oncoming_leaves_time``; a dropped
    sweep shows nothing of it, so the move goes back): the oncoming lane is the greater danger. Back into the left lane:
    when that lane would break the specification once the AV is wholly in it, at the move's end (a vehicle alongside,
    the vehicle ahead too near at its closing speed, a follower that blocks), and the oncoming lane leaves time to
    move back and return again; judged at the move's end, not at the action's as the fallback's return is, so that
    only what finishing the move would break sends the AV back towards the oncoming lane. Past
    ``MinimalRisk.reverse_within_s`` the move goes on."""
    if done_s > MINIMAL_RISK.reverse_within_s + 1e-9:
        return False
    if to_lane is Lane.RIGHT:
        return not oncoming_leaves_time(a, speed_mps, left_s + RETURN_S)
    lead = a.lead
    blocked = (alongside(readings) or follower_blocks(a, speed_mps, left_s)
               or (lead is not None and lead.too_near_after(lead.closing_mps(speed_mps), left_s)))
    return blocked and oncoming_leaves_time(a, speed_mps, done_s + RETURN_S)


def waiting_mps(a: Around, speed_mps: float, near: bool, beside: bool, blocks: bool) -> float | None:
    """The speed the fallback drives at while it waits in the right lane for room (None: the one it has), the lowest
    of the targets its neighbours set (``MinimalRisk``'s rules, from the fitted closing speeds; a vehicle ahead not
    measured yet may stand):

    - the vehicle ahead too near (``near``): its speed; beside the AV (its centre ahead of the AV's), ``open_mps``
      slower than the vehicle it drops back behind (``drop_back_to``), unless the AV is the faster and passing it
      ends sooner (``MinimalRisk.pass_s`` against ``drop_back_s``): then ``open_mps`` faster than it, or the speed
      the AV has when that is more; while passing a vehicle alongside behind, only a gap ahead that breaks the
      specification now holds the AV back (matching the vehicle ahead held it beside the one it passed);
    - a vehicle alongside behind (``beside``) or a follower that ``blocks``: at least ``open_mps`` faster than it
      when the AV is the faster, or passing it ends sooner than dropping back and the left lane has a slot ahead of
      it then (``room_ahead_of``); else ``open_mps`` slower than it (it drops back); a follower too near (not
      alongside) that keeps its speed: its speed. Beside a vehicle faster than ``open_mps`` a standstill is never the
      target."""
    mr, targets = MINIMAL_RISK, []
    f, lead = a.follower, a.lead
    f_own_mps = None if f is None else f.own_mps(speed_mps)
    passing = False  # beside a vehicle the AV passes (its centre behind the AV's)
    if beside and f is not None and f_own_mps is not None and f.gap_m < SAFETY.min_gap_m:
        f_closing_mps = f_own_mps - speed_mps
        pass_s = mr.pass_s(-f_closing_mps, -f.dx_m)
        passing = f_closing_mps < -CLOSING_EPS_MPS or (
            pass_s < mr.drop_back_s(-f_closing_mps, -f.dx_m, f_own_mps)
            and room_ahead_of(f, f_own_mps, lead, speed_mps, pass_s))
    if near and lead is not None:
        closing = lead.closing_mps(speed_mps)
        lead_mps = max(0.0, speed_mps - closing)
        if passing and not lead.too_near_after(closing, 0.0):
            pass  # the gap ahead meets the specification now: on past the vehicle beside, not held beside it
        elif lead.gap_m >= SAFETY.min_gap_m:
            targets.append(lead_mps)
        elif (lead_own_mps := lead.own_mps(speed_mps)) is not None:
            # beside it: ``open_mps`` below the speed of the vehicle it drops behind, not the AV's (a target under the
            # AV's own speed every step ratchets it to a standstill beside a reading moving away)
            behind_m, behind_mps = drop_back_to(lead, f, speed_mps, lead_own_mps)
            if lead_own_mps >= speed_mps - CLOSING_EPS_MPS or mr.drop_back_s(
                    speed_mps - behind_mps, behind_m, behind_mps) <= mr.pass_s(speed_mps - lead_own_mps, lead.dx_m):
                targets.append(max(0.0, behind_mps - mr.open_mps))
            else:
                targets.append(max(speed_mps, lead_own_mps + mr.open_mps))
    if f is not None and f_own_mps is not None and (beside or blocks):
        if passing:  # at least ``open_mps`` faster than it, so that the pass ends
            targets.append(max(speed_mps, f_own_mps + mr.open_mps))
        elif f.gap_m < SAFETY.min_gap_m and f_own_mps >= speed_mps - CLOSING_EPS_MPS:  # not passing: drop back
            targets.append(max(0.0, f_own_mps - mr.open_mps))
        elif blocks:  # its speed, a standstill at the least (a fit may put a standing vehicle below one)
            targets.append(max(0.0, f_own_mps))
    return min(targets) if targets else None


def ramp_mps(command_mps: float, target_mps: float | None, decel_mps2: float, dt_s: float,
             accel_mps2: float | None = MINIMAL_RISK.accel_mps2) -> float:
    """One control step's speed command on the way from ``command_mps`` to ``target_mps`` (None: keep it): down at
    ``decel_mps2``, up at ``accel_mps2`` (None: never up)."""
    if target_mps is None:
        return command_mps
    if command_mps > target_mps:
        return max(target_mps, command_mps - decel_mps2 * dt_s)
    if accel_mps2 is None:
        return command_mps
    return min(target_mps, command_mps + accel_mps2 * dt_s)


def wait_command(a: Around, speed_mps: float, beside: bool, command_mps: float, waited_s: float,
                 dt_s: float) -> float | None:
    """The fallback in the right lane, one control step: None when it returns now (nothing alongside, the vehicle
    ahead not nearer than the specification allows at the fitted closing speed once a return at the speed it starts
    at is over, no follower that ``follower_blocks``; or ``MinimalRisk.ends_wait`` after ``waited_s``, the oncoming
    lane the greater danger, unless beside a left-lane vehicle: then only once the oncoming vehicle would come within
    the least gap, ``alongside_now``); else its next speed command, towards ``waiting_mps`` (down at the car's
    braking limit, up at ``accel_mps2``)."""
    closing = 0.0 if a.lead is None else a.lead.closing_mps(speed_mps)
    near = a.lead is not None and a.lead.too_near_after(closing, RETURN_S)
    blocks = follower_blocks(a, speed_mps)
    if not beside and not near and not blocks:
        return None
    leaves = oncoming_leaves_time(a, speed_mps, gap_only=alongside_now(a, beside))
    if MINIMAL_RISK.ends_wait(waited_s, a.swept, leaves):
        return None
    target = waiting_mps(a, speed_mps, near, beside, blocks)
    return ramp_mps(command_mps, target, MINIMAL_RISK.emergency_decel_mps2, dt_s)


def return_profile(a: Around, speed_mps: float) -> SpeedProfile:
    """The return's speed reference from ``speed_mps``: that speed, unless the vehicle ahead would then be nearer
    than the specification allows at the return's end (only a return the oncoming lane forces starts so): then it
    brakes, at the car's limit, down to that vehicle's speed by the fitted closing speed (not fitted yet: the slowest
    the bounds let a vehicle ahead be, not a standstill), from the start, or once it is clear of a vehicle alongside
    it is passing (``pass_first_s``)."""
    lead = a.lead
    if lead is None:
        return SpeedProfile(speed_mps, ())
    if lead.measured_mps is not None:
        closing = min(speed_mps, lead.closing_mps(speed_mps))
    else:
        closing = max(0.0, speed_mps - (a.bounds.same_mps.low_mps if a.bounds is not None else 0.0))
    if closing <= 0.0 or not lead.too_near_after(closing, RETURN_S):
        return SpeedProfile(speed_mps, ())
    brake_s = closing / MINIMAL_RISK.emergency_decel_mps2
    return SpeedProfile(speed_mps, (Ramp(pass_first_s(a.follower, lead, speed_mps, closing), brake_s, -closing),))


def too_near_now(a: Around, speed_mps: float) -> bool:
    """Whether the sensed vehicle ahead is nearer than the safety specification allows at the closing speed at the
    car's own ``speed_mps`` (``Nearest.closing_mps``): the emergency brake's trigger (``brake_command``), and what
    ends the fallback's return once its sideways move is over (the AV in the left lane) for the brake in lane. The
    return's profile was chosen at its start, from the closing speed fitted then; a vehicle that brakes harder
    meanwhile (to a standstill, below its lane's bounds) closes faster than that."""
    lead = a.lead
    return lead is not None and lead.too_near_after(lead.closing_mps(speed_mps), 0.0)


def in_lane_hold_mps(emergency: bool, speed_mps: float, slowest_ahead_mps: float) -> float:
    """The speed the minimal-risk manoeuvre holds in lane: the fallback's (``emergency``) the slowest a vehicle ahead
    may be, from below as from above; a proved continuation's never faster than the AV already is."""
    mr = MINIMAL_RISK
    return mr.fallback_hold_mps(slowest_ahead_mps) if emergency else mr.hold_mps(speed_mps, slowest_ahead_mps)


def may_open_gap(a: Around) -> bool:
    """Whether the gap ahead is one the fallback may open (``MinimalRisk.open_mps`` slower than the vehicle ahead):
    a vehicle ahead nearer than the one behind, which stays farther than the specification allows at the opening's
    closing speed. Whether a decision needs it opened is the planner's to say."""
    if not a.swept or a.lead is None:
        return False
    rear_m = a.follower.gap_m if a.follower is not None else float("inf")
    return a.lead.gap_m < rear_m and not SAFETY.violated(rear_m, MINIMAL_RISK.open_mps)


def brake_command(a: Around, speed_mps: float, command_mps: float, hold_mps: float, emergency: bool,
                  room_needed: Callable[[float], bool], dt_s: float) -> float:
    """One control step of braking in lane: towards ``hold_mps`` at ``MinimalRisk.decel_mps2``; with ``emergency``
    (the fallback) also up to it at ``accel_mps2``, and, while the sensed vehicle ahead is nearer than the safety
    specification allows at the closing speed at the car's own ``speed_mps`` (``Nearest.closing_mps``), down to that
    vehicle's speed at the car's braking limit, never up, and on below it while the measured gap still closes (the
    car may run above its command); where the fallback may open the gap ahead (``may_open_gap``) and a decision at
    the hand-back speed would find no safe step in lane (``room_needed``, asked only then), ``open_mps`` below the
    vehicle ahead's speed."""
    mr = MINIMAL_RISK
    target, decel = hold_mps, mr.decel_mps2
    lead = a.lead
    if emergency and lead is not None:
        closing = lead.closing_mps(speed_mps)
        if too_near_now(a, speed_mps):
            # never up while it is too near: the command the car runs above, or the speed of a vehicle that does not
            # close, would keep the gap as near as it is
            target, decel = min(command_mps, max(0.0, speed_mps - closing)), mr.emergency_decel_mps2
            if (now_mps := lead.closing_now_mps(speed_mps)) is not None and now_mps > CLOSING_EPS_MPS:
                target = min(target, max(0.0, command_mps - decel * dt_s))  # it still closes
        elif (lead_own_mps := lead.own_mps(speed_mps)) is not None and may_open_gap(a) and \
                room_needed(mr.handback_mps(speed_mps, hold_mps)):
            target = min(hold_mps, max(0.0, lead_own_mps - mr.open_mps))
    return ramp_mps(command_mps, target, decel, dt_s, mr.accel_mps2 if emergency else None)
