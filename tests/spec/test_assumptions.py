"""The sound model's assumptions: named profiles whose numbers follow from the world's stated parameters by the rule
each states, and one line of bad input for every unusable number."""

from __future__ import annotations

from dataclasses import replace

import pytest

from spec.assumptions import PROFILES, Bounds, SpeedBounds, check_bounds, profile
from spec.errors import OptionError
from spec.lanes import Lane
from spec.physical import NOISE, SENSORS, SPEEDS, TRAFFIC


def test_the_default_profile_is_the_spread_traffics_cut_off_and_three_sd_of_the_sensing_noise() -> None:
    bounds = profile("default")
    low, high = SPEEDS.mean_mps - SPEEDS.cut_sd * SPEEDS.sd_mps, SPEEDS.mean_mps + SPEEDS.cut_sd * SPEEDS.sd_mps
    assert bounds.same_mps == bounds.oncoming_mps == SpeedBounds(low, high)
    assert (low, high) == pytest.approx((4.9, 9.1))
    assert bounds.sensing_error_m == pytest.approx(3 * NOISE.range_sd_m) and bounds.phantoms
    assert all(word in bounds.source for word in ("SPEEDS", "NOISE", "phantoms"))


def test_the_paper_profile_keeps_every_vehicle_at_the_common_speed() -> None:
    bounds = profile("paper")
    assert bounds.speeds(Lane.LEFT) == bounds.speeds(Lane.RIGHT) == SpeedBounds(TRAFFIC.speed_mps, TRAFFIC.speed_mps)
    assert bounds.sensing_error_m == 0.0


def test_phantoms_stand_at_the_ends_of_the_sensors_ranges_and_only_where_the_profile_has_them() -> None:
    where = {(p.lane, p.dx_m) for p in profile("default").phantom_vehicles()}
    assert where == {(Lane.LEFT, SENSORS.left_range_m), (Lane.LEFT, -SENSORS.left_range_m),
                     (Lane.RIGHT, SENSORS.right_range_m)}
    assert replace(profile("default"), phantoms=False).phantom_vehicles() == ()


GOOD = PROFILES["default"]


@pytest.mark.parametrize(("bounds", "words"), [
    (replace(GOOD, same_mps=SpeedBounds(-1.0, 9.0)), ["--same-mps", "-1.0", "at least 0"]),
    (replace(GOOD, oncoming_mps=SpeedBounds(5.0, float("nan"))), ["--oncoming-mps", "nan", "finite"]),
    (replace(GOOD, same_mps=SpeedBounds(9.0, 5.0)), ["--same-mps", "9..5", "lower end is above"]),
    (replace(GOOD, sensing_error_m=float("inf")), ["sensing-error-m", "inf", "finite"]),
    (replace(GOOD, sensing_error_m=-0.5), ["sensing-error-m", "-0.5", "at least 0"]),
    (replace(GOOD, sensing_error_m=2000.0), ["sensing-error-m", "2000", "larger than the sensed window"]),
])
def test_an_unusable_bound_is_bad_input_naming_the_key_the_value_and_why(bounds: Bounds, words: list[str]) -> None:
    with pytest.raises(OptionError) as caught:
        check_bounds(bounds)
    assert caught.value.exit_code == 2 and all(word in str(caught.value) for word in words), str(caught.value)


def test_an_unknown_profile_is_bad_input_listing_the_known_ones() -> None:
    with pytest.raises(OptionError, match=r"--bounds='psychic'.*known: paper, default"):
        profile("psychic")


def test_every_traffic_and_sensing_model_has_its_bounds_rule() -> None:
    from sim.parts import SENSOR_MODELS, TRAFFIC_MODELS
    from spec.assumptions import SENSING_RULES, TRAFFIC_SPEEDS

    assert sorted(TRAFFIC_SPEEDS) == sorted(TRAFFIC_MODELS) and sorted(SENSING_RULES) == sorted(SENSOR_MODELS)


def test_the_worlds_bounds_are_the_named_profiles_where_the_world_is_theirs() -> None:
    from spec.assumptions import world_bounds

    assert world_bounds("spread", "noisy") == profile("default")  # same numbers: the same assumptions
    assert world_bounds("paper", "exact") == profile("paper")
    following = world_bounds("following", "noisy")
    assert following.same_mps == profile("default").same_mps and following.phantoms
    assert world_bounds("spread", "noisy", range_sd_m=1.0).sensing_error_m == pytest.approx(3.0)


def test_a_bounds_scale_widens_speeds_about_their_middle_never_below_a_standstill() -> None:
    from spec.assumptions import world_bounds

    wide, narrow = world_bounds("spread", "noisy", scale=2.0), world_bounds("spread", "noisy", scale=0.5)
    assert (wide.same_mps.low_mps, wide.same_mps.high_mps) == pytest.approx((2.8, 11.2))
    assert (narrow.same_mps.low_mps, narrow.same_mps.high_mps) == pytest.approx((5.95, 8.05))
    assert wide.sensing_error_m == pytest.approx(3.0) and narrow.sensing_error_m == pytest.approx(0.75)
    assert world_bounds("spread", "exact", scale=10.0).same_mps.low_mps == 0.0
    assert world_bounds("paper", "exact", scale=2.0).same_mps == profile("paper").same_mps  # no width to scale


@pytest.mark.parametrize(("args", "named"), [(("nosuch", "exact"), "--traffic"), (("paper", "nosuch"), "--sensor"),
                                             (("paper", "exact", 0.5, -1.0), "--bounds-scale"),
                                             (("paper", "exact", 0.5, float("nan")), "--bounds-scale"),
                                             (("paper", "noisy", float("inf")), "--range-sd-m")])
def test_the_worlds_bounds_refuse_unknown_models_and_unusable_numbers(args: tuple[object, ...], named: str) -> None:
    from spec.assumptions import world_bounds

    with pytest.raises(OptionError) as refused:
        world_bounds(*args)  # type: ignore[arg-type]
    assert refused.value.key == named
