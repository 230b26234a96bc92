"""The engines' table of windows (``spec.windows``) is the interpreter's windows, state by state."""

from __future__ import annotations

import random
from dataclasses import replace

import pytest

from spec.actions import ACTION_RULES, Action
from spec.assumptions import PROFILES, profile
from spec.escapes import COMMIT
from spec.grid import grid_for
from spec.lanes import Lane
from spec.sound import Sound, SoundRules, SoundState, advance
from spec.windows import Instant, Window, declared, sound_table

CELLS_M = (21.0, 10.5, 7.0, 5.25)


def _close(a: Instant, b: Instant) -> bool:
    return all(abs(x - y) <= 1e-9 for x, y in ((a.t_s, b.t_s), (a.x_m, b.x_m), (a.v_mps, b.v_mps)))


def _assert_same(got: Window, want: Window) -> None:
    assert _close(got.boundary, want.boundary) and _close(got.end, want.end)
    assert len(got.stretches) == len(want.stretches)
    for g, w in zip(got.stretches, want.stretches, strict=True):
        assert (g.left, g.right, g.entering, g.at_start) == (w.left, w.right, w.entering, w.at_start)
        assert len(g.pieces) == len(w.pieces)
        for gb, wb in zip(g.pieces, w.pieces, strict=True):
            assert all(_close(x, y) for x, y in zip((gb.start, gb.ahead, gb.oncoming, gb.behind),
                                                    (wb.start, wb.ahead, wb.oncoming, wb.behind)))
            assert abs(gb.end_s - wb.end_s) <= 1e-9 and gb.rear == wb.rear


@pytest.mark.parametrize("cell_m", CELLS_M)
@pytest.mark.parametrize("name", sorted(PROFILES))
@pytest.mark.parametrize("start_mps", [None, 3.0, 9.5])
def test_the_table_gives_every_window_of_a_walk_as_the_interpreter_computes_it(cell_m: float, name: str,
                                                                               start_mps: float | None) -> None:
    """Under the commitment semantics too, each step window cut where the ramp into a following action of another
    speed starts, as ``SoundRules.step_violation`` cuts it for a sequence known whole."""
    grid = grid_for(cell_m)
    sound = replace(Sound(profile(name), commitment=COMMIT), start_mps=start_mps)
    table, rules = sound_table(sound, grid), SoundRules(sound, Lane.RIGHT, (), (), grid, ())
    rng = random.Random(2026)
    for _ in range(60):
        state = SoundState(rng.choice(list(Lane)), 0, 0, 0, 0, None, None)
        for _ in range(10):
            enabled = [a for a in Action if ACTION_RULES[a].from_lane in (None, state.lane)]
            for action in (*enabled, None):
                ref = rules.reference(state, action)
                boundary = Instant(ref.boundary_s, ref.position_m(ref.boundary_s), ref.speed_mps(ref.boundary_s))
                window = rules.window(state, action)
                _assert_same(table.state_window(state, action), declared(window, boundary))
                for following in Action if action is not None else ():
                    cut = rules.cut_s(state.t_units, action, following)
                    kept = window if cut is None else rules.cut_window(window, cut)
                    _assert_same(table.state_window(state, action, following), declared(kept, boundary))
            action = rng.choice(enabled)
            state = advance(state, action, grid, rules.speeds[action])


def test_whole_plans_have_no_cut_windows() -> None:
    """Only a sequence known whole asks for a cut window: the whole-plan semantics' table holds none."""
    grid = grid_for(21.0)
    assert not sound_table(Sound(profile("default")), grid).relative_cut
    committed = sound_table(Sound(profile("default"), commitment=COMMIT), grid)
    assert committed.relative_cut and committed.early_cut


def test_a_measured_start_speed_makes_early_windows() -> None:
    """The ramp from a measured speed into the first action makes the first windows depend on where the plan
    started; without one (the common speed) only the speed-changing first actions do."""
    grid = grid_for(21.0)
    common, measured = sound_table(Sound(profile("default")), grid), sound_table(
        Sound(profile("default"), start_mps=3.0), grid)
    assert 0 < len(common.early) < len(measured.early)
