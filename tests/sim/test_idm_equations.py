"""The Intelligent Driver Model against its published equations (Treiber, Hennecke and Helbing, Phys. Rev. E 62,
1805 (2000), eqs. 1-2 and Table I), worked out in the test for a follower behind one leader:

    s*(v, dv) = s0 + max(0, v T + v dv / (2 sqrt(a b)))        a_IDM = a [1 - (v / v0)^delta - (s* / s)^2]

with the desired speed v0 drawn per vehicle (here: given), so that a fault in the desired gap (the v dv term
dropped or of the wrong sign, v T or s0 missing, sqrt(a b) replaced by a b) or in the free-road term fails here."""

from __future__ import annotations

import math

import pytest

from sim.idm import idm_accel_mps2
from spec.physical import IDM

# Table I of the paper (the desired speed aside), and the physical bound the simulator adds.
T_S, S0_M, A_MPS2, B_MPS2, DELTA = 1.6, 2.0, 0.73, 1.67, 4.0
MAX_DECEL_MPS2 = 9.0


def desired_gap_m(v: float, dv: float) -> float:
    return S0_M + max(0.0, v * T_S + v * dv / (2.0 * math.sqrt(A_MPS2 * B_MPS2)))


def published_accel_mps2(v: float, v0: float, s: float, dv: float) -> float:
    interaction = 0.0 if s == math.inf else (desired_gap_m(v, dv) / s) ** 2
    return A_MPS2 * (1.0 - (v / v0) ** DELTA - interaction)


def test_the_spec_states_the_published_parameters() -> None:
    assert (IDM.time_gap_s, IDM.min_gap_m, IDM.accel_mps2, IDM.comfortable_decel_mps2, IDM.exponent) == (
        T_S, S0_M, A_MPS2, B_MPS2, DELTA)
    assert IDM.max_decel_mps2 == MAX_DECEL_MPS2


# (v, v0, s, dv): the follower's speed, its desired speed, the bumper-to-bumper gap and the closing speed
CASES = {
    "closing": (7.0, 7.5, 30.0, 1.0),  # s* = 2 + 11.2 + 7 / (2 sqrt(1.2191)) = 16.37 m
    "closing fast": (9.0, 8.0, 40.0, 4.0),  # above its desired speed and closing at 4 m/s
    "falling back": (7.0, 7.5, 30.0, -1.5),  # v T + v dv / (2 sqrt(a b)) = 11.2 - 4.76 > 0
    "falling back fast": (5.0, 7.0, 12.0, -6.0),  # 8 - 13.6 < 0: s* = s0
    "same speed": (6.0, 7.0, 15.0, 0.0),  # s* = s0 + v T = 11.6 m
    "standing behind a standing leader": (0.0, 7.0, 10.0, 0.0),  # s* = s0: a (1 - (2 / 10)^2)
}


@pytest.mark.parametrize("case", CASES)
def test_the_acceleration_behind_a_leader_is_the_published_one(case: str) -> None:
    v, v0, s, dv = CASES[case]
    expected = published_accel_mps2(v, v0, s, dv)
    assert expected > -MAX_DECEL_MPS2  # within the physical bound: the equations alone decide
    assert idm_accel_mps2(v, v0, s, dv) == pytest.approx(expected, abs=1e-9)


def test_the_cases_exercise_each_term_of_the_desired_gap() -> None:
    """Each case above differs from its value with one term of s* changed by more than 0.01 m/s^2, so each
    term is tested (not only the equations' overall shape)."""
    terms = {
        "v dv": lambda v, dv: S0_M + max(0.0, v * T_S),
        "sign of v dv": lambda v, dv: S0_M + max(0.0, v * T_S - v * dv / (2.0 * math.sqrt(A_MPS2 * B_MPS2))),
        "sqrt(a b)": lambda v, dv: S0_M + max(0.0, v * T_S + v * dv / (2.0 * A_MPS2 * B_MPS2)),
        "v T": lambda v, dv: S0_M + max(0.0, T_S + v * dv / (2.0 * math.sqrt(A_MPS2 * B_MPS2))),
        "s0": lambda v, dv: max(0.0, v * T_S + v * dv / (2.0 * math.sqrt(A_MPS2 * B_MPS2))),
    }
    for term, wrong_gap in terms.items():
        differs = [c for c, (v, v0, s, dv) in CASES.items()
                   if abs(A_MPS2 * ((desired_gap_m(v, dv) / s) ** 2 - (wrong_gap(v, dv) / s) ** 2)) > 0.01]
        assert differs, term


def test_a_closing_follower_wants_a_longer_gap_than_one_falling_back() -> None:
    """The sign of the dynamic term: at the same speed and gap, closing brakes harder than holding, which brakes
    harder than falling back."""
    closing, holding, falling = (idm_accel_mps2(7.0, 7.5, 30.0, dv) for dv in (1.0, 0.0, -1.0))
    assert closing < holding < falling


@pytest.mark.parametrize(("v", "v0"), [(0.0, 7.0), (5.0, 7.0), (7.0, 7.0), (8.0, 7.0)])
def test_on_a_free_road_the_acceleration_is_a_times_one_minus_the_speed_ratio_to_the_fourth(v: float,
                                                                                           v0: float) -> None:
    expected = A_MPS2 * (1.0 - (v / v0) ** 4)
    assert idm_accel_mps2(v, v0, math.inf, 3.0) == pytest.approx(expected, abs=1e-9)  # no leader: dv is moot
    assert idm_accel_mps2(v, v0, math.inf, 0.0) == pytest.approx(published_accel_mps2(v, v0, math.inf, 0.0),
                                                                 abs=1e-9)


def test_the_equilibrium_gap_at_the_desired_gap_of_a_slow_leader_holds_speed() -> None:
    """Behind a leader at the same speed v (dv = 0), the acceleration is zero where (s* / s)^2 = 1 - (v / v0)^4:
    s = (s0 + v T) / sqrt(1 - (v / v0)^4)."""
    v, v0 = 6.0, 7.5
    s_m = (S0_M + v * T_S) / math.sqrt(1.0 - (v / v0) ** 4)
    assert idm_accel_mps2(v, v0, s_m, 0.0) == pytest.approx(0.0, abs=1e-9)


def test_braking_is_bounded_by_the_stated_physical_limit() -> None:
    """10 m/s, closing at 5 m/s, 3 m behind: the equations ask for far more than 9 m/s^2; the bound gives 9."""
    assert published_accel_mps2(10.0, 7.0, 3.0, 5.0) < -10 * MAX_DECEL_MPS2
    assert idm_accel_mps2(10.0, 7.0, 3.0, 5.0) == -MAX_DECEL_MPS2
