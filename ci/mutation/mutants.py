"""Single-rule faults the project's own checks must catch: each is one exact text replacement in one file.

``python -m ci.mutation.check`` applies each to a scratch copy of the checkout and runs the detectors
``.ci/run`` runs, cheapest first, until one catches it. A mutant is kept only if it changes
behaviour somewhere: an equivalent one would be a test that cannot fail. One such was measured
and left out: swapping the cost's first two terms (lane changes, right-lane steps) in the Z3
objective changes no plan, since every plan of a model and start lane has the same number of
lane changes except in preparations case B, where the plan without a lane change also has no
right-lane step. Another was measured and replaced: counting a target alongside the AV as
behind it (``spec.rules.behind_line`` one cell later) changes no plan, since the goal wants the
AV in its own lane, where a vehicle alongside is a collision. Three of the commitment semantics' were
measured and left out (2026-12-03, each against its continuous-motion checks and a sweep of 1,700 answers): an
escape's end taken as safe for ever unchecked (after an escape's own steps the minimal-risk manoeuvre's ramp only
slows the AV, and no answer changed where the checks could see it), a step's window known whole cut a whole ramp
before its boundary instead of half (the stretch it leaves unchecked is never the worst instant: the next window
starts later and holds it), and every escape tried from either lane (a physically empty manoeuvre the model
checks as consistently as the motions do: a fault of progress, not of safety). One of Spin's translation of measured
speeds was measured and left out (2026-12-04): a measured follower held to its lane's top instead of its own changes
no answer, since wherever followers keep their speed and a same-direction speed was measured the minimal-risk
manoeuvre brakes to a standstill, below every top, so a plan never ends in the left lane with a follower, and a
follower faster than the lane's top refuses the steps beside it either way. For the same reason (the manoeuvre
ends at a standstill) so does Spin's plan end behind a measured vehicle checked as the lane's vehicles are (closing in
only above the lane's slowest speed).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Mutant:
    """One fault: in ``path``, ``old`` (which occurs exactly once) becomes ``new``."""

    name: str
    path: str
    old: str
    new: str
    what: str
    tests: tuple[str, ...] = ()  # test files written for it outside its module's mirror, tried with that mirror first


MUTANTS: tuple[Mutant, ...] = (
    # -- Spin (the Promela printer) ---------------------------------------------------------------
    Mutant("promela-danger-zone", "promela/render.py", "    return hi - av\n", "    return max(0, hi - av - 1)\n",
           "the oncoming danger zone one cell narrower in Promela"),
    Mutant("promela-no-check-after-tick", "promela/render.py",
           "right[i] = right[i] - 1; i++ :: else -> break od; collide() }",
           "right[i] = right[i] - 1; i++ :: else -> break od }",
           "no collision check after an oncoming tick in Promela"),
    Mutant("promela-goal-on-crashed-path", "promela/render.py",
           "finish = (f'if :: !crashed -> printf", "finish = (f'if :: true -> printf",
           "the goal checked on a path that has crashed, in Promela"),
    Mutant("promela-lane-change-limit", "promela/render.py", 'guard.append("lc < MAX_LC")',
           'guard.append("lc <= MAX_LC")', "one lane change more than the model allows, in Promela"),
    Mutant("promela-horizon", "promela/render.py", 'guard = ["!crashed", "steps < horizon",',
           'guard = ["!crashed", "steps <= horizon",', "one step beyond the horizon, in Promela"),
    Mutant("spin-unknown-ending-no-plan", "promela/runner.py",
           '    raise EngineError(f"pan failed ({_ending(returncode)}): {_first_line(text)}")\n',
           '    return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored, "pan ended")\n',
           "an unrecognised ending of pan (a signal, unknown output) answered as no plan within the horizon"),
    Mutant("spin-signal-is-an-ending", "promela/runner.py",
           "    if returncode == 0 and summary is not None:",
           "    if returncode <= 0 and summary is not None:",
           "a pan killed by a signal read like a clean exit"),
    Mutant("spin-unclean-report-is-no-plan", "promela/runner.py",
           "        if errors == 0 and _clean_report(text):",
           "        if errors == 0:",
           "a report that is not pan's clean one (interrupted, a warning, an unknown line) answered as no plan"),
    Mutant("promela-left-path-landing-only", "promela/render.py",
           "    path = list(left_path(shift)) if shift else []",
           "    path = [shift] if shift else []",
           "a left-lane vehicle checked only where it ends, not in every cell it passes, in Promela (finer grids)"),
    # -- Z3 -----------------------------------------------------------------------------------------
    Mutant("z3-cost-order", "oracle/bmc.py",
           "        for index, name in enumerate(COST_TERMS):\n            floor, best = ",
           "        for index, name in enumerate((*COST_TERMS[:2], COST_TERMS[3], COST_TERMS[2])):\n"
           "            floor, best = ",
           "brakes and plan length swapped in the Z3 objective"),
    Mutant("z3-warm-start-skips-a-bound", "oracle/bmc.py",
           "start, not_before = guess, [z3.Not(kept.goal(k)) for k in range(guess)]",
           "start, not_before = guess + 1, [z3.Not(kept.goal(k)) for k in range(guess + 1)]",
           "Z3's shortest, warm-started, skips the bound it guessed"),
    Mutant("z3-goal-lane", "oracle/bmc.py", "            parts.append(s.right == (goal.av_lane is Lane.RIGHT))",
           "            parts.append(True)", "the goal's lane condition dropped in the Z3 encoding"),
    Mutant("z3-oncoming-passed", "oracle/bmc.py", "c - s.o <= passed_line(grid))",
           "c - s.o <= passed_line(grid) + 1)", "'oncoming passed' one cell late in the Z3 encoding"),
    Mutant("z3-left-path-landing-only", "oracle/bmc.py",
           "for i, c in enumerate(self.left) for j in left_path(shift)]",
           "for i, c in enumerate(self.left) for j in (shift,)]",
           "a left-lane vehicle checked only where it ends, not in every cell it passes, in Z3 (finer grids)"),
    # -- the interpreter and its searches -------------------------------------------------------------
    Mutant("interpreter-no-check-after-tick", "oracle/interpreter.py",
           "        hit = collision_in(after, rules, grid, tick)\n", "        hit = None\n",
           "no collision check after an oncoming tick in the interpreter's step"),
    Mutant("offsets-oncoming-passed", "oracle/abstraction.py",
           "o_at_least = max(scenario.right_lane) - passed_line(grid)",
           "o_at_least = min(scenario.right_lane) - passed_line(grid)",
           "'oncoming passed' waits for the nearest oncoming vehicle only, in the offset form"),
    Mutant("bitplan-no-smear", "oracle/bitplan.py", "        for i in range(0, len(flat.smear), 2):",
           "        for i in range(0, 0, 2):", "the bitset search's end-row smear dropped (finer grids)"),
    # -- spec/ and the discretiser --------------------------------------------------------------------
    Mutant("spec-danger-zone", "spec/models.py", "danger_m=Fraction(21), max_lane_changes=2),  # one paper cell",
           "danger_m=Fraction(42), max_lane_changes=2),  # one paper cell",
           "the final model's danger zone twice as long (every engine follows: the library's plans change)"),
    Mutant("discretiser-oncoming-rounding", "spec/cells.py",
           "    return grid.av_cell + math.trunc(dx_m / grid.cell)",
           "    return grid.av_cell + round(dx_m / grid.cell)",
           "an oncoming vehicle's cell rounded away from the AV"),
    # -- the conformance properties and their coverage ---------------------------------------------
    Mutant("crossval-no-plan-proof-at-horizon", "ci/conformance/properties.py",
           "\nDEEPER = 2\n",
           "\nDEEPER = 1\n",
           "no_plan_proof searches only up to the horizon, not beyond it"),
    Mutant("crossval-trace-prefix", "ci/conformance/properties.py",
           "    return None if len(ours) == len(theirs) else min(len(ours), len(theirs))\n",
           "    return None\n",
           "trace_equality compares the traces only as far as the shorter goes (a missing or extra state passes)"),
    Mutant("coverage-never-in-passing", "oracle/coverage.py",
           "    return problem_collision(problem, landed) is None\n",
           "    return False\n",
           "rule coverage never sees a left-lane vehicle hit in passing (finer grids look covered when they are not)"),
    # -- the simulator --------------------------------------------------------------------------------
    Mutant("sim-no-oncoming-contacts", "sim/simulator.py",
           "car = first_contact(self.scene, self.car.body, self.traffic.cars())",
           "car = first_contact(self.scene, self.car.body, self.traffic.left)",
           "contacts with oncoming vehicles ignored by the simulator"),
    Mutant("sim-no-left-contacts", "sim/simulator.py",
           "car = first_contact(self.scene, self.car.body, self.traffic.cars())",
           "car = first_contact(self.scene, self.car.body, self.traffic.oncoming)",
           "contacts with same-direction vehicles ignored by the simulator"),
    Mutant("executor-heading-ignored", "sim/driver/control.py",
           "/ max(MIN_HEADING_COS, math.cos(car.yaw_rad))", "/ 1.0",
           "the executor's speed command not corrected for the car's heading: a lane change from a slow queue falls "
           "more than the envelope's 1.5 m behind its reference"),
    Mutant("fallback-brake-closing-at-hold-speed", "sim/driver/fallback.py",
           "        closing = lead.closing_mps(speed_mps)\n        if too_near_now(a, speed_mps):",
           "        closing = lead.closing_mps(hold_mps)\n        if too_near_now(a, hold_mps):",
           "the fallback's emergency brake reads the closing speed on the vehicle ahead at the hold speed, not at the "
           "car's own: behind a vehicle slower than the hold speed it brakes on below that vehicle's speed"),
    Mutant("fallback-return-kept-whole", "sim/driver/sound.py",
           "stop=lambda: fallback.too_near_now(self.around(), h.pose().along_mps)", "stop=lambda: False",
           "the fallback's return runs to its end at the speed chosen at its start, whatever the vehicle ahead does "
           "meanwhile: one braking to a standstill is hit", ("tests/sim/test_sound_loop.py",)),
    Mutant("monitor-refine-drops-the-sensing-error", "sim/driver/monitor.py",
           "wide = [(r.interval_m[0] - error_m, r.interval_m[1] + error_m) for r in readings]",
           "wide = [r.interval_m for r in readings]",
           "the last proof's sets narrow a reading taken as exact: a vehicle up to the sensing error from its reading "
           "is left out of the sets a plan is proved against"),
    Mutant("sound-reference-ages-at-the-cars-speeds", "spec/sound.py",
           "slack = 0.0 if self.from_reference else 2 * self.tracking.speed_mps",
           "slack = 2 * self.tracking.speed_mps",
           "a plan from the proved reference ages its vehicles against every speed the car may have about it, where "
           "the reference holds the start speed: a start the last proof holds breaks the specification by centimetres"),
    Mutant("driver-plans-from-the-readings-alone", "sim/driver/sound.py",
           "sets = self.refined(readings, pose) if holds else None", "sets = None",
           "a decision whose last proof holds plans from the snapshot's readings alone: a noisy reading nearer than "
           "the proof's sets finds the start unsafe twice and the fallback takes over with no assumption broken",
           ("tests/sim/test_sound_loop.py",)),
    Mutant("fallback-emergency-brake-speeds-up", "sim/driver/fallback.py",
           "target, decel = min(command_mps, max(0.0, speed_mps - closing)), mr.emergency_decel_mps2",
           "target, decel = max(0.0, speed_mps - closing), mr.emergency_decel_mps2",
           "the fallback's emergency brake takes the speed of a too-near vehicle that does not close as its target: "
           "the car running above its command at the hold speed raises the command past it, and the gap stays"),
    Mutant("driver-reference-start-chases-the-reference", "sim/driver/decide.py",
           "> tracking.speed_mps - SPEED_LAG_MPS:", "> tracking.speed_mps:",
           "a plan starts on the reference whenever the car is within the envelope's speed error of it, the pull back "
           "towards the reference included: a car a metre behind chases a reference that brakes, past the envelope"),
    Mutant("sound-phantoms-follow-the-sensors-one-way", "spec/sound.py",
           "(ahead if p.dx_m > 0 else -ahead)", "ahead",
           "a plan from the reference moves the phantoms behind the AV as far away as those ahead: a vehicle from "
           "beyond the rear sensor's range may be that much nearer than the plan assumes"),
    Mutant("driver-breach-ends-no-committed-part", "sim/driver/sound.py",
           "stop=lambda: self.interrupt and h.swept(),", "stop=None,",
           "a breach the AV senses does not end the proved action under way: the decision runs on past it to the "
           "action's end"),
    Mutant("driver-kept-escape-off-its-proofs-clock", "sim/driver/sound.py",
           'since=self.boundary))', 'since=None))',
           "a kept escape starts from its own beginning wherever the reference stands, not where and when the proof "
           "has it after the steps since the last action ended"),
    Mutant("driver-hand-over-forgets-the-move", "sim/driver/sound.py",
           "scenario = self.moving(self.planner.scenario(readings, lane, pose.along_mps, view_m), moving_s)",
           "scenario = self.planner.scenario(readings, lane, pose.along_mps, view_m)",
           "a decision taken during a sideways move plans as if the AV were wholly in the lane it names: finishing "
           "or undoing the move is proved without the time the AV still spends in both lanes"),
    Mutant("executor-handed-move-jumps", "sim/executor.py",
           "                self.sideways = Sideways(y_from, y_to, lateral_s, done_s) if handed is to_lane else \\\n"
           "                    Sideways(y_ref, y_from, done_s, 0.0)\n",
           "                self.sideways = None\n",
           "a sideways move handed over is dropped: the lateral reference jumps to the lane's centre instead of going "
           "on along the move the decision proved", ("tests/sim/test_physics.py",)),
    Mutant("fallback-reverse-ignores-oncoming", "sim/driver/fallback.py",
           "    return blocked and oncoming_leaves_time(a, speed_mps, done_s + RETURN_S)",
           "    return blocked",
           "a return to the left lane cut short whatever the oncoming lane leaves: the AV goes back into the "
           "oncoming lane with a vehicle closing on it"),
    Mutant("decide-unsafe-start-kept-again", "sim/driver/decide.py",
           "unsafe_again = status is Status.UNSAFE_START and unsafe_before and not pending",
           "unsafe_again = status is Status.UNSAFE_START and unsafe_before and pending",
           "a start that breaks the safety specification again, nothing of the last plan left, keeps the last "
           "decision's minimal-risk manoeuvre (which holds the broken gap) instead of handing over to the fallback"),
    Mutant("traffic-oncoming-odds-reversed", "sim/traffic.py",
           "    odds = np.array([float(f) for f in spec.oncoming_gap_odds])",
           "    odds = np.array([float(f) for f in spec.oncoming_gap_odds][::-1])",
           "the paper's odds for oncoming spawn gaps reversed"),
    Mutant("traffic-four-in-a-row", "sim/traffic.py", "if g > 1 or run < spec.max_consecutive]",
           "if g > 1 or run <= spec.max_consecutive]", "four left-lane vehicles spawned without an empty cell"),
    Mutant("tolerance-plan-one-sided", "sim/tolerance.py",
           "else ViolationKind.PLAN if abs(deviation) > self.plan_tolerance else None)",
           "else ViolationKind.PLAN if deviation > self.plan_tolerance else None)",
           "the plan tolerance checked on one side only (a vehicle falling behind its prediction passes)"),
    Mutant("traffic-oncoming-odds-first-two-swapped", "sim/traffic.py",
           "p=odds / odds.sum()",
           "p=odds[[1, 0, 2, 3]] / odds.sum()",
           "the oncoming spawn odds of 8 and 12 cells swapped (1/4, 1/8, 1/4, 3/8)"),
    Mutant("spec-oncoming-odds-first-two-swapped", "spec/physical.py",
           "(Fraction(1, 8), Fraction(1, 4), Fraction(1, 4), Fraction(3, 8))",
           "(Fraction(1, 4), Fraction(1, 8), Fraction(1, 4), Fraction(3, 8))",
           "the paper's oncoming odds stated wrongly in spec/ (the sampler and the old tests read the same numbers)",
           ("tests/sim/test_spawn_odds.py",)),
    Mutant("traffic-respawn-ahead-of-a-vehicle-beside-the-av", "sim/traffic.py",
           "if front - av_x_m < CAR.length_m:", "if front < av_x_m:",
           "a left-lane vehicle respawned a gap ahead of a front-most one beside the AV (not wholly ahead of it), "
           "where it can appear beside or inside the AV", ("tests/sim/test_models_by_hand.py",)),
    Mutant("traffic-initial-run-one-short", "sim/traffic.py",
           "            self.run = self.run + 1 if gap == 1 else 1  # the vehicle just placed",
           "            self.run = self.run + 1 if gap == 1 else 0  # the vehicle just placed",
           "the first platoon counted one short: four left-lane vehicles in a row at the start"),
    Mutant("idm-desired-gap-no-dynamic-term", "sim/idm.py",
           "speed_mps * spec.time_gap_s + speed_mps * closing_mps",
           "speed_mps * spec.time_gap_s + 0 * speed_mps * closing_mps",
           "the v dv / (2 sqrt(a b)) term dropped from IDM's desired gap"),
    Mutant("safety-closing-reversed", "sim/safety.py",
           "pose.along_mps - car.velocity_mps",
           "car.velocity_mps - pose.along_mps",
           "the safety monitor's closing speed to the vehicle ahead reversed"),
    Mutant("tolerance-doubled", "sim/tolerance.py", "ViolationKind.STEP if added > self.step_tolerance",
           "ViolationKind.STEP if added > 2 * self.step_tolerance", "the step tolerance check twice as lax"),
    Mutant("tracking-beyond-gate-a-dt", "sim/tracking.py",
           "CAR.max_accel_mps2 * dt_s * dt_s", "CAR.max_accel_mps2 * dt_s",
           "the tracker follows a reading ahead of its vehicle's interval by a x dt, not a x dt^2, as that vehicle"),
    Mutant("tracking-entering-without-sensing-error", "sim/tracking.py",
           "self.bounds.speeds(lane).high_mps) * dt_s + e_m", "self.bounds.speeds(lane).high_mps) * dt_s",
           "a new reading near a range edge explained as entering only within a sweep's travel, the sensing error "
           "left out"),
    Mutant("containment-reading-error-doubled", "sim/driver/monitor.py",
           "    error_m, (lo, hi) = bounds.sensing_error_m, r.interval_m",
           "    error_m, (lo, hi) = 2 * bounds.sensing_error_m, r.interval_m",
           "the AV's monitor allows a reading twice its own sensing error: it senses a breach 1.5 m late"),
    Mutant("tracking-speed-braking-dt-squared", "spec/tracking.py",
           "max(0.0, speed[0] - change.brake_mps2 * dt_s)", "max(0.0, speed[0] - change.brake_mps2 * dt_s * dt_s)",
           "a track's speed interval grown between sweeps by b x dt^2, not b x dt: a vehicle braking hard leaves it",
           ("tests/sim/test_tracking_speed.py",)),
    Mutant("dynamics-least-travel-half-braking", "spec/dynamics.py",
           "return (Phase(0.0, stop_s, 0.0, low_mps, -brake_mps2),",
           "return (Phase(0.0, stop_s, 0.0, low_mps, -brake_mps2 / 2),",
           "a measured vehicle's least travel taken braking at half b_max: one braking hard is behind its bound"),
    Mutant("sound-move-under-way-ignored", "spec/sound.py",
           "            if self.move_s > 0:\n                segments = self._moving(segments, action is None)\n",
           "",
           "a sideways move under way at the start is not laid over the windows: the AV is proved as if wholly in "
           "the lane it moves into from the first instant"),
    Mutant("sound-measured-ahead-never-brakes", "spec/sound.py",
           "for ph in (d.slowest if conflict is Conflict.AHEAD else d.fastest):",
           "for ph in (d.fastest if conflict is Conflict.AHEAD else d.fastest):",
           "a measured vehicle ahead held to its fastest motion, never braking: the AV closes on one that stops",
           ("tests/oracle/test_sound_measured.py",)),
    Mutant("sound-measured-hold-lane-slowest", "spec/sound.py",
           "        return 0.0\n    return sound.bounds.same_mps.low_mps",
           "        return sound.bounds.same_mps.low_mps\n    return sound.bounds.same_mps.low_mps",
           "the minimal-risk manoeuvre holds the lane's slowest speed where a measured vehicle ahead may stop",
           ("tests/oracle/test_sound_measured.py",)),
    Mutant("sound-measured-speeds-not-aged", "spec/sound.py",
           "None if own is None else own.aged(sound.bounds.latency_s)))", "None if own is None else own))",
           "a measured vehicle's speed interval not aged by the snapshot's age, in the one place the interpreter and "
           "Spin read it from: cross-validation cannot see it, the motions (which age it themselves) do",
           ("tests/oracle/test_sound_measured.py",)),
    Mutant("dynamics-held-from-the-snapshot", "spec/dynamics.py",
           "    if high_mps >= top_mps or hold_from_s <= 0:",
           "    if high_mps >= top_mps or hold_from_s < math.inf:",
           "a vehicle held from a passing window on taken as never speeding up from the snapshot on",
           ("tests/spec/test_dynamics.py",)),
    Mutant("sound-cut-in-always-held", "spec/sound.py",
           "                dynamics = v.dynamics\n                if held_from_s is not None:",
           "                dynamics = v.dynamics.held_from(0.0)\n                if held_from_s is not None:",
           "a measured vehicle cut in ahead of taken as never speeding up, without the no-acceleration profile",
           ("tests/oracle/test_sound_measured.py",)),
    Mutant("containment-overtaken-held-from-the-snapshot", "sim/driver/monitor.py",
           "return held_vehicle(v, self.windows_s, elapsed_s)",
           "return held_vehicle(v, tuple((0.0, t1) for _, t1 in self.windows_s), elapsed_s)",
           "containment holds a vehicle overtaken to the speed it had at the snapshot, not when the AV moved out",
           ("tests/sim/test_containment.py",)),
    Mutant("tracking-speed-reading-half-its-error", "spec/tracking.py",
           "return max(0.0, speed_mps - error_mps), speed_mps + error_mps",
           "return max(0.0, speed_mps - error_mps / 2), speed_mps + error_mps",
           "a range-rate reading taken as allowing half its error bound below it",
           ("tests/sim/test_tracking_speed.py",)),
    # -- the sound model (every engine would share these declarations: the continuous-motion checks must see them)
    # -- the sound model's translations, one engine each (caught by crossval --model sound) ------------
    Mutant("spin-sound-widening-a-tick-late", "promela/sound.py",
           "{\treturn S_LO[i] + SAME_LOW * (a->t + dt) < a->x + dx + E_X + LEN + a->gap + EPS_M;",
           "{\treturn S_LO[i] + SAME_LOW * (a->t + dt + UNIT_S) < a->x + dx + E_X + LEN + a->gap + EPS_M;",
           "Spin's translation widens a vehicle ahead one time unit late (its slowest end assumed farther)"),
    Mutant("spin-sound-rounding-inwards", "promela/sound.py",
           "lo = measured ? v[at++] : ONCOMING_EXTENT[cell][0];",
           "lo = measured ? v[at++] : ONCOMING_EXTENT[cell][0] + CELL_M / 2;",
           "Spin's translation rounds an oncoming vehicle's cell inwards (its near end half a cell farther)"),
    Mutant("spin-served-table-of-another-request", "promela/sound.py",
           "	if (table_loaded != NULL && strcmp(table_loaded, path) == 0) { return; }",
           "	if (table_loaded != NULL) { return; }",
           "a served verifier keeps the first table it read whatever table a later request names",
           ("tests/promela/test_sound_spin.py",)),
    Mutant("spin-sound-phantom-dropped", "promela/sound.py",
           "for (j = 0; j < N_PHANTOMS; j++)  /* the unseen stretch",
           "for (j = 1; j < N_PHANTOMS; j++)  /* the unseen stretch",
           "Spin's translation drops the first phantom (the same-direction one beyond the left sensor's range)"),
    Mutant("spin-sound-envelope-ignored", "promela/sound.py",
           "    ahead = s.required_gap_m(b.ahead.v_mps + e_v - same.low_mps)",
           "    ahead = s.required_gap_m(b.ahead.v_mps - same.low_mps)",
           "Spin's translation ignores the AV's speed error in the gap it requires ahead"),
    Mutant("z3-sound-widening-a-tick-late", "oracle/bmc_sound.py",
           "            need = self._ahead_need(b.ahead) + EPS_M\n",
           "            need = self._ahead_need(b.ahead) - self.low * self.table.unit_s + EPS_M\n",
           "Z3's translation widens a vehicle ahead one time unit late (its slowest end assumed farther)"),
    Mutant("z3-sound-trusts-an-expected-length", "oracle/bmc_sound.py",
           "            if verdict == z3.unsat:\n                start, not_before = guess,",
           "            if verdict == z3.unsat or expected is not None:\n                start, not_before = guess,",
           "Z3's shortest takes a cross-check's expected length as proved least (its check below it ignored)",
           ("tests/oracle/test_bmc_sound.py",)),
    Mutant("z3-sound-rounding-inwards", "oracle/bmc_sound.py",
           "[(lo - f, hi + f) for lo, hi in oncoming]",
           "[(lo + grid.cell / 2 - f, hi + f) for lo, hi in oncoming]",
           "Z3's translation rounds an oncoming vehicle's cell inwards (its near end half a cell farther)"),
    Mutant("z3-sound-phantom-dropped", "oracle/bmc_sound.py",
           "        for p in sound.phantoms():",
           "        for p in sound.phantoms()[1:]:",
           "Z3's translation drops the first phantom (the same-direction one beyond the left sensor's range)"),
    Mutant("z3-sound-envelope-ignored", "oracle/bmc_sound.py",
           "self.gap(at.v_mps + self.ev - self.low)",
           "self.gap(at.v_mps - self.low)",
           "Z3's translation ignores the AV's speed error in the gap it requires ahead"),
    Mutant("spin-measured-least-travel-half-braking", "promela/sound.py",
           "m->slow[0].accel = -B_MAX;", "m->slow[0].accel = -B_MAX / 2;",
           "Spin's translation of a measured vehicle's least travel brakes at half b_max"),
    Mutant("spin-measured-own-error-ignored", "promela/sound.py",
           "if (j < n_same) { S_LO[j] = v[at]; S_HI[j] = v[at + 1]; }",
           "if (0) { S_LO[j] = v[at]; S_HI[j] = v[at + 1]; }",
           "Spin widens a measured same-direction vehicle by the lane-wide error, not by its own (its speed's reach "
           "while the snapshot ages)"),
    Mutant("spin-overtaken-held-from-the-snapshot", "promela/sound.py",
           "held_s = now.out >= 0 ? now.out * UNIT_S : (now.lane == RIGHT ? 0.0 : -1.0);", "held_s = 0.0;",
           "Spin holds a measured vehicle cut in ahead of from the snapshot on, not from when the AV moved out"),
    Mutant("spin-sound-latency-ignored", "promela/sound.py",
           "sound.start_error_m(Lane.LEFT),",
           "sound.bounds.sensing_error_m,",
           "Spin's translation ignores the snapshot's age in the left lane: the sensing error alone widens a "
           "same-direction vehicle"),
    Mutant("z3-sound-latency-ignored", "oracle/bmc_sound.py",
           "    e, f = sound.start_error_m(Lane.LEFT), sound.start_error_m(Lane.RIGHT)",
           "    e, f = sound.bounds.sensing_error_m, sound.start_error_m(Lane.RIGHT)",
           "Z3's translation ignores the snapshot's age in the left lane: the sensing error alone widens a "
           "same-direction vehicle"),
    Mutant("sound-no-widening", "spec/sound.py",
           'out.append(Vehicle(key, i, lo - e, hi + e, f"{key.value}_lane[{i}] (cell {cell})",',
           'out.append(Vehicle(key, i, lo, hi, f"{key.value}_lane[{i}] (cell {cell})",',
           "sensed vehicles not widened by the sensing error"),
    Mutant("sound-rounding-inwards", "spec/cells.py",
           "lo, hi = (offset - 0.5) * grid.cell, (offset + 0.5) * grid.cell",
           "lo, hi = (offset - 0.25) * grid.cell, (offset + 0.25) * grid.cell",
           "a same-direction cell taken as its middle half (rounded inwards, not outwards)"),
    Mutant("sound-time-gap-halved", "spec/sound.py",
           "base + s.time_gap_s * (p.v0_mps + tr.speed_mps - low)",
           "base + s.time_gap_s / 2 * (p.v0_mps + tr.speed_mps - low)",
           "half the time gap to a vehicle ahead (a safe distance too short)"),
    Mutant("sound-goal-oncoming-nearest-end", "spec/sound.py",
           "not self.passed(v, x_m, t_s) for v in self.oncoming if v.index is not None))",
           "self.oncoming_low(v, t_s) + length > x_m for v in self.oncoming if v.index is not None))",
           "an oncoming vehicle counted past the AV when its nearest position is (not every position)",
           ("tests/oracle/test_bmc_sound.py",)),  # Z3's goal, translated apart, disagrees: 246 s later by crossval
    Mutant("sound-phantoms-dropped", "spec/sound.py",
           "    for p in sound.phantoms():  # the whole unseen stretch",
           "    for p in sound.phantoms()[:0]:  # the whole unseen stretch",
           "no phantom: traffic from beyond the sensors' ranges ignored"),
    Mutant("sound-envelope-ignored-ahead", "spec/sound.py",
           "        base = p.x0_m - low * p.t0_s + tr.position_m + s.vehicle_length_m",
           "        base = p.x0_m - low * p.t0_s + s.vehicle_length_m",
           "the AV's position error ignored towards a vehicle ahead"),
    # -- Spin's proofs for the commitment semantics (promela.sound's probes): caught by the pinned witnesses in its
    # tests, which hold its probes to the interpreter's sequence by sequence ---------------------------------------
    Mutant("spin-commit-step-never-cut", "promela/sound.py",
           "\tif (next >= 0 && ACTION_SPEED[next] != ACTION_SPEED[action])",
           "\tif (0 && next >= 0 && ACTION_SPEED[next] != ACTION_SPEED[action])",
           "Spin checks a step known to be followed by another of a different speed to its end at its own speed",
           ("tests/promela/test_commit.py",)),
    Mutant("spin-commit-escape-counts-lane-changes", "promela/sound.py",
           "guard.append(\"(seq || lc < MAX_LC)\")",
           "guard.append(\"lc < MAX_LC\")",
           "Spin's probed escape refused for the model's count of lane changes (the abort back after the move out)",
           ("tests/promela/test_commit.py",)),
    Mutant("z3-commit-step-never-cut", "oracle/bmc_sound.py",
           "            window = table.state_window(state, action, following)\n",
           "            window = table.state_window(state, action)\n",
           "Z3 checks a step known to be followed by another of a different speed to its end at its own speed",
           ("tests/oracle/test_bmc_commit.py",)),
    Mutant("z3-measured-checked-only-while-braking", "oracle/bmc_own.py",
           "        for ph in phases:\n            u0, u1 = max(t0_s, ph.t0_s), min(t1_s, ph.t1_s)",
           "        for ph in phases[:1]:\n            u0, u1 = max(t0_s, ph.t0_s), min(t1_s, ph.t1_s)",
           "Z3 checks a measured vehicle over the first phase of its travel bound only (braking, not standing after "
           "it; speeding up, not holding its top)", ("tests/oracle/test_bmc_commit.py",)),
    Mutant("z3-measured-follower-at-its-lanes-top", "oracle/bmc_own.py",
           "                if rear_binds(self.sound.bounds, slowest, v):",
           "                if rear_binds(self.sound.bounds, slowest):",
           "Z3 holds a measured follower in the AV's lane to its lane's top, not to its own",
           ("tests/oracle/test_bmc_commit.py",)),
    # -- the commitment semantics (spec.commitment, every engine's): each caught by the continuous-motion checks ----
    Mutant("commit-one-action-past-its-escape", "spec/commitment.py",
           "        if escape is not None:\n            return plan[:n], escape",
           "        if escape is not None:\n            return plan[: n + 1], escape",
           "the committed part one action longer than the escape was proved after",
           ("tests/oracle/test_commit.py",)),
    Mutant("commit-escape-skips-its-first-action", "spec/commitment.py",
           "        if proofs.holds((*committed, *escape.actions), goal=False):",
           "        if proofs.holds((*committed, *escape.actions[1:]), goal=False):",
           "an escape proved without its first action (the abort's return, the completion's speeding past)",
           ("tests/oracle/test_commit.py",)),
    Mutant("commit-whole-plan-goal-unchecked", "spec/commitment.py",
           "    if most == len(plan) and proofs.holds(plan, goal=True):",
           "    if most == len(plan) and proofs.holds(plan, goal=False):",
           "a predicted plan taken as a whole proved plan without its goal for every position (no escape kept)",
           ("tests/oracle/test_commit.py",)),
)


def mutant(name: str) -> Mutant:
    found = {m.name: m for m in MUTANTS}.get(name)
    if found is None:
        from spec.errors import OptionError

        raise OptionError("--mutants", name, f"unknown mutant (known: {', '.join(m.name for m in MUTANTS)})")
    return found
