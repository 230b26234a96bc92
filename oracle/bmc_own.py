"""Z3's conditions on the vehicles that move by their own dynamics (measured speeds, ``spec.dynamics``), for a
sequence known whole (the commitment semantics: every state known, ``oracle.bmc_sound.SoundEncoding.holds``).

A measured vehicle's travel bounds are its phases (``Dynamics.slowest``: braking to a standstill; ``fastest``:
speeding up to its top, or until the no-acceleration profile holds it), each quadratic in time, and so is the AV's
reference over a window's piece. Where the interpreter takes the worst instant of each piece in closed form
(``SoundRules._own_need``) and Spin translates that, Z3 is asked whether some instant of the piece breaks the
condition: each violation is a formula over a time variable of its own (free, so existential), quadratic in it,
and the sequence holds when their disjunction is unsatisfiable (nonlinear real arithmetic, decided). Conditions
at a known instant (held ahead, passed, the goal) are constants. The conditions are ``spec/windows.py``'s and
``spec.sound``'s: AHEAD, ONCOMING, entering (certainly ahead or certainly behind over the whole move; a cut-in's
vehicle held from the passing window's start under ``Overtaken.NO_ACCELERATION``), BEHIND for followers where
they bind (``spec.sound.rear_binds`` at the vehicle's own top), the continuation's end (a vehicle that may stop
closes in on any moving AV; one still braking when the manoeuvre ends, AHEAD until it stands), and the goal.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TypeAlias

import z3

from spec.commitment import ProofIncomplete
from spec.dynamics import Dynamics, Overtaken, Phase
from spec.lanes import Lane
from spec.models import GoalRule
from spec.scenario import Scenario
from spec.sound import EPS_M, Vehicle, follower_limit_m, rear_binds, scenario_vehicles
from spec.windows import Binding, Instant, Stretch, Window

Cond: TypeAlias = z3.BoolRef | bool
#: (time, the reference's position, its speed) -> (a travel bound, its speed) -> the violation at that instant
Body = Callable[[z3.ArithRef, z3.ArithRef, z3.ArithRef, z3.ArithRef, z3.ArithRef], z3.BoolRef]


def _r(value: float) -> z3.ArithRef:
    return z3.RealVal(value)


def _bool(c: Cond) -> z3.BoolRef:
    return z3.BoolVal(c) if isinstance(c, bool) else c


def _travel(ph: Phase, t: z3.ArithRef) -> tuple[z3.ArithRef, z3.ArithRef]:
    """A phase's travel and speed at ``t`` (within it)."""
    s = t - _r(ph.t0_s)
    return _r(ph.travel_m) + _r(ph.speed_mps) * s + _r(ph.accel_mps2) * s * s / 2, _r(ph.speed_mps) + _r(
        ph.accel_mps2) * s


def _at(phases: Sequence[Phase], t_s: float) -> z3.ArithRef:
    """A travel bound at a known instant (its phase then: ``spec.dynamics``' rule)."""
    ph = next((p for p in phases if t_s < p.t1_s), phases[-1])
    return z3.simplify(_travel(ph, _r(t_s))[0])


class Own:
    """A scenario's measured vehicles and their conditions (``same`` and ``oncoming`` by their index in its
    lanes; empty when no speed was measured)."""

    def __init__(self, scenario: Scenario) -> None:
        sound = scenario.sound
        assert sound is not None
        self.sound = sound
        own = [v for v in scenario_vehicles(scenario) if v.dynamics is not None and v.index is not None]
        self.same = {v.index: v for v in own if v.lane is Lane.LEFT and v.index is not None}
        self.oncoming = {v.index: v for v in own if v.lane is Lane.RIGHT and v.index is not None}
        #: the indices the lane-wide conditions leave to these (``oracle.bmc_sound.Skip``)
        self.skip_same, self.skip_oncoming = frozenset(self.same), frozenset(self.oncoming)
        self.held_passing = sound.overtaken is Overtaken.NO_ACCELERATION and bool(self.same)
        self.ex, self.ev = sound.tracking.position_m, sound.tracking.speed_mps
        self.length_m = sound.safety.vehicle_length_m
        self.g_min, self.tau = sound.safety.min_gap_m, sound.safety.time_gap_s

    def __bool__(self) -> bool:
        return bool(self.same or self.oncoming)

    # -- at a known instant ---------------------------------------------------------------------------------
    def held(self, i: int, at: Instant) -> z3.BoolRef:
        """Same-direction ``i`` clear ahead of the AV at ``at`` for every position (held to AHEAD)."""
        v = self.same[i]
        assert v.dynamics is not None
        return _r(v.lo_m) + _at(v.dynamics.slowest, at.t_s) - _r(self.length_m) >= _r(at.x_m + self.ex)

    def passed(self, j: int, at: Instant) -> z3.BoolRef:
        """Oncoming ``j`` certainly past the AV at ``at``."""
        v = self.oncoming[j]
        assert v.dynamics is not None
        return _r(v.hi_m) - _at(v.dynamics.slowest, at.t_s) + _r(self.length_m) <= _r(at.x_m - self.ex - EPS_M)

    # -- some instant of a stretch of time --------------------------------------------------------------------
    @staticmethod
    def _some(t0_s: float, t1_s: float, x0_m: float, v0_mps: float, acc_mps2: float, phases: Sequence[Phase],
              body: Body) -> z3.BoolRef:
        """Some instant of ``[t0_s, t1_s]`` (the reference from ``x0_m`` at ``v0_mps``, accelerating at ``acc_mps2``)
        at which ``body`` holds, in one of the phases of a travel bound."""
        out = []
        for ph in phases:
            u0, u1 = max(t0_s, ph.t0_s), min(t1_s, ph.t1_s)
            if u1 < u0 or (u1 == u0 and t1_s > t0_s):
                continue
            t = z3.FreshReal("t")
            s = t - _r(t0_s)
            x, v = _r(x0_m) + _r(v0_mps) * s + _r(acc_mps2) * s * s / 2, _r(v0_mps) + _r(acc_mps2) * s
            travel, speed = _travel(ph, t)
            bounds = [t >= _r(u0)] + ([t <= _r(u1)] if math.isfinite(u1) else [])
            out.append(z3.And(*bounds, body(t, x, v, travel, speed)))
        return z3.Or(*out) if out else z3.BoolVal(False)

    def _over(self, b: Binding, phases: Sequence[Phase], body: Body) -> z3.BoolRef:
        return self._some(b.start.t_s, b.end_s, b.start.x_m, b.start.v_mps, b.acc_mps2, phases, body)

    def _ahead(self, lo: float) -> Body:
        """AHEAD broken: ``lo + D(t) < x(t) + e_x + L + max(g_min, tau (v(t) + e_v - V(t))) + EPS``."""
        def body(t: z3.ArithRef, x: z3.ArithRef, v: z3.ArithRef, d: z3.ArithRef, dv: z3.ArithRef) -> z3.BoolRef:
            near = x + _r(self.ex + self.length_m + EPS_M) - d
            return z3.Or(_r(lo) < near + _r(self.g_min), _r(lo) < near + _r(self.tau) * (v + _r(self.ev) - dv))
        return body

    def _oncoming(self, lo: float) -> Body:
        """ONCOMING broken: ``lo - D(t) < x(t) + e_x + L + max(g_min, tau (v(t) + e_v + V(t))) + EPS``."""
        def body(t: z3.ArithRef, x: z3.ArithRef, v: z3.ArithRef, d: z3.ArithRef, dv: z3.ArithRef) -> z3.BoolRef:
            near = x + _r(self.ex + self.length_m + EPS_M) + d
            return z3.Or(_r(lo) < near + _r(self.g_min), _r(lo) < near + _r(self.tau) * (v + _r(self.ev) + dv))
        return body

    def _behind(self, hi: float) -> Body:
        """A vehicle behind the AV too near (CUT_IN, BEHIND): ``hi + D(t) > x(t) - e_x - L - max(g_min, tau (V(t) -
        v(t) + e_v)) - EPS``."""
        def body(t: z3.ArithRef, x: z3.ArithRef, v: z3.ArithRef, d: z3.ArithRef, dv: z3.ArithRef) -> z3.BoolRef:
            far = x - _r(self.ex + self.length_m + EPS_M) - d
            return z3.Or(_r(hi) > far - _r(self.g_min), _r(hi) > far - _r(self.tau) * (dv - v + _r(self.ev)))
        return body

    # -- a window ---------------------------------------------------------------------------------------------
    def broken(self, window: Window, follows: Sequence[Cond], held_s: float | None = None) -> list[z3.BoolRef]:
        """Each way the measured vehicles may break ``window`` (known, absolute); ``follows``: the followers;
        ``held_s``: a move back from the passing lane, its window's start (``SoundRules.passing_from_s``)."""
        out: list[z3.BoolRef] = []
        for s in window.stretches:
            if s.left:
                out += self._entering(s, held_s) if s.entering else self._in_lane(s, follows)
            if s.right:
                out += [z3.And(z3.Not(self.passed(j, b.start)), self._over(b, self._dyn(v).fastest,
                                                                           self._oncoming(v.lo_m)))
                        for b in s.pieces for j, v in self.oncoming.items()]
        return out

    @staticmethod
    def _dyn(v: Vehicle) -> Dynamics:
        assert v.dynamics is not None
        return v.dynamics

    def _entering(self, s: Stretch, held_s: float | None) -> list[z3.BoolRef]:
        out = []
        for v in self.same.values():
            d = self._dyn(v)
            ahead = z3.Or(*[self._over(b, d.slowest, self._ahead(v.lo_m)) for b in s.pieces])
            if s.at_start:  # already in the lane: one that cannot be clear ahead follows
                limit = follower_limit_m(s.pieces[0].start.x_m, self.sound)
                behind: z3.BoolRef = _r(v.hi_m) > _r(limit - EPS_M)
            else:
                fast = (d if held_s is None else d.held_from(held_s)).fastest
                behind = z3.Or(*[self._over(b, fast, self._behind(v.hi_m)) for b in s.pieces])
            out.append(z3.And(ahead, behind))
        return out

    def start_broken(self, window: Window, follows: Sequence[Cond]) -> list[z3.BoolRef]:
        """At the start in the left lane, then as in it (``spec.sound.SoundRules.start_violation``): the start
        stretch's in-lane conditions, ``follows`` its followers."""
        return [c for s in window.stretches if s.left and s.at_start for c in self._in_lane(s, follows)]

    def _in_lane(self, s: Stretch, follows: Sequence[Cond]) -> list[z3.BoolRef]:
        out = []
        for b in s.pieces:
            slowest = min(b.start.v_mps, b.start.v_mps + b.acc_mps2 * (b.end_s - b.start.t_s))
            for i, v in self.same.items():
                d, f = self._dyn(v), _bool(follows[i])
                out.append(z3.And(z3.Not(f), self.held(i, b.start), self._over(b, d.slowest, self._ahead(v.lo_m))))
                if rear_binds(self.sound.bounds, slowest, v):
                    out.append(z3.And(f, self._over(b, d.fastest, self._behind(v.hi_m))))
        return out

    def end_broken(self, window: Window, lane: Lane, follows: Sequence[Cond]) -> list[z3.BoolRef]:
        """After the continuation (its end ``window.end``): an oncoming vehicle not passed; a follower that closes in
        for ever; a vehicle held ahead that may stop while the AV still moves, or is still braking when the AV
        holds its end speed (AHEAD until it stands)."""
        end = window.end
        if lane is Lane.RIGHT:
            return [z3.Not(self.passed(j, end)) for j in self.oncoming]
        out = []
        for i, v in self.same.items():
            d, f = self._dyn(v), _bool(follows[i])
            if rear_binds(self.sound.bounds, end.v_mps, v):  # a follower that keeps its speed closes in for ever
                out.append(f)
            if self.sound.minimal_risk.closes_in(end.v_mps, 0.0):
                out.append(z3.And(z3.Not(f), self.held(i, end)))
                continue
            stop_s = d.speed_mps[0] / d.change.brake_mps2
            if stop_s > end.t_s:
                braking = self._some(end.t_s, stop_s, end.x_m, end.v_mps, 0.0, d.slowest, self._ahead(v.lo_m))
                out.append(z3.And(z3.Not(f), self.held(i, end), braking))
        return out

    def goal(self, window: Window, lane: Lane, goal: GoalRule, targets: Sequence[int],
             sensed_oncoming: int) -> list[Cond]:
        """The goal's conditions on the measured vehicles it names, at the continuation window's boundary."""
        at, ex, length, out = window.boundary, self.ex, self.length_m, list[Cond]()
        if goal.targets_behind:
            out += [_r(self.same[i].hi_m) + _at(self._dyn(self.same[i]).fastest, at.t_s) <= _r(at.x_m - ex - length)
                    for i in targets if i in self.same]
        if goal.nearest_target_m is not None and targets and targets[0] in self.same:
            v = self.same[targets[0]]
            d = self._dyn(v)
            out.append(_r(v.lo_m) + _at(d.slowest, at.t_s) - _r(at.x_m + ex + length) >= 0)
            most_m = float(goal.nearest_target_m)
            out.append(_r(v.hi_m) + _at(d.fastest, at.t_s) - _r(at.x_m - ex + length) <= _r(most_m))
        if goal.oncoming_passed:
            out += [self.passed(j, at) for j in self.oncoming if j < sensed_oncoming]
        return out


def unbroken(broken: Sequence[z3.BoolRef], timeout_s: float | None) -> bool:
    """Whether no instant breaks any of ``broken`` (their disjunction unsatisfiable); past ``timeout_s``: the proof
    is incomplete."""
    if not broken:
        return True
    solver = z3.SolverFor("QF_NRA")
    if timeout_s is not None:
        solver.set("timeout", max(1, int(timeout_s * 1000)))
    solver.add(z3.Or(*broken))
    found = solver.check()
    if found == z3.unknown:
        raise ProofIncomplete(f"z3: a measured vehicle's conditions undecided ({solver.reason_unknown()})")
    return found == z3.unsat
