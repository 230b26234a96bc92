"""The nearest vehicles the fallback reads (``sim.driver.nearest``): which one each is, and the closing speeds fitted
through the last sweeps with the AV's own motion taken out."""

from __future__ import annotations

import pytest

from sim.driver.nearest import Nearest
from sim.driver.readings import Reading
from spec.envelope import MINIMAL_RISK
from spec.lanes import Lane


def test_the_lead_is_the_nearest_vehicle_ahead_and_its_closing_speed_is_fitted_only_on_the_same_one() -> None:

    sweep = (Reading(Lane.LEFT, 1, 30.0), Reading(Lane.LEFT, 2, 9.0), Reading(Lane.LEFT, 3, -8.0),
             Reading(Lane.RIGHT, 4, 5.0))
    first = Nearest.after(None, sweep, 10.0)
    assert first == Nearest(9.0, None, (9.0,))
    closer = Nearest.after(first, (Reading(Lane.LEFT, 2, 8.5),), 10.0)
    assert closer is not None and closer.dx_m == 8.5 and closer.measured_mps is None  # two readings: not measured
    closer = Nearest.after(closer, (Reading(Lane.LEFT, 2, 8.0),), 10.0)
    assert closer is not None and closer.measured_mps == pytest.approx(5.0)
    another = Nearest.after(closer, (Reading(Lane.LEFT, 1, 29.5),), 10.0)
    assert another == Nearest(29.5, None, (29.5,))  # another vehicle
    assert Nearest.after(closer, None, 10.0) is None  # a dropped sweep: nothing sensed
    assert Nearest.after(closer, (Reading(Lane.LEFT, 3, -7.0),), 10.0) is None  # nothing ahead
    lead = None
    for k in range(3 * MINIMAL_RISK.fit_sweeps):
        lead = Nearest.after(lead, (Reading(Lane.LEFT, 2, 20.0 - 0.3 * k),), 10.0)
    assert lead is not None and len(lead.distances_m) == MINIMAL_RISK.fit_sweeps
    assert lead.measured_mps == pytest.approx(3.0)


def test_the_fallbacks_closing_speeds_take_the_avs_own_speed_changes_out_and_follow_its_speed_between_sweeps(
        ) -> None:
    """The AV speeds up at 2.7 m/s2 from 8.5 m/s behind a vehicle at 7 m/s (seed 48 of the reliability campaign at
    c2c5ab8, whose fit said 2.2 m/s closing where it was 2.8, and whose return came within 0.6 m of it), with a
    vehicle behind at 7 m/s: at each sweep the closing speeds are the true ones at the AV's speed then, and between
    sweeps they move with the AV's speed; the vehicles' own speeds stay 7 m/s."""

    lead = follower = None
    for k in range(2 * MINIMAL_RISK.fit_sweeps):
        t = k / 10.0
        av_m, av_mps = 8.5 * t + 2.7 * t * t / 2, 8.5 + 2.7 * t
        sweep = (Reading(Lane.LEFT, 1, 30.0 + 7.0 * t - av_m), Reading(Lane.LEFT, 2, -20.0 + 7.0 * t - av_m))
        lead = Nearest.after(lead, sweep, 10.0, travelled_m=1000.0 + av_m, av_mps=av_mps)
        follower = Nearest.after(follower, sweep, 10.0, behind=True, travelled_m=1000.0 + av_m, av_mps=av_mps)
        if k >= 2:
            assert lead is not None and lead.measured_mps == pytest.approx(av_mps - 7.0, abs=1e-6)
            assert follower is not None and follower.measured_mps == pytest.approx(7.0 - av_mps, abs=1e-6)
    assert lead is not None and follower is not None
    later_mps = av_mps + 0.27  # a tenth of a second on
    assert lead.closing_now_mps(later_mps) == pytest.approx(later_mps - 7.0, abs=1e-6)
    assert follower.closing_now_mps(later_mps) == pytest.approx(7.0 - later_mps, abs=1e-6)
    assert lead.own_mps(later_mps) == pytest.approx(7.0) and follower.own_mps(later_mps) == pytest.approx(7.0)
    assert lead.closing_mps(later_mps) == pytest.approx(later_mps - 7.0, abs=1e-6)
    # in a sideways move the fit takes the AV's speed along the road; a change after the sweep, along its heading
    yawed = None
    for k in range(4):
        yawed = Nearest.after(yawed, (Reading(Lane.LEFT, 1, 20.0 + (7.0 - 9.9) * k / 10.0),), 10.0,
                              travelled_m=9.9 * k / 10.0, av_mps=10.0, along_mps=9.9)
    assert yawed is not None and yawed.measured_mps == pytest.approx(9.9 - 7.0, abs=1e-6)
    assert yawed.closing_now_mps(10.5) == pytest.approx(9.9 - 7.0 + 0.5, abs=1e-6)
    # without the AV's odometer (the tests' views): the distances' own fit, at the speed asked about
    plain = Nearest(12.0, 2.0)
    assert plain.closing_now_mps(9.0) == 2.0 and plain.own_mps(9.0) == 7.0


def test_the_follower_and_the_oncoming_vehicle_are_the_nearest_behind_and_ahead_in_their_lanes() -> None:

    follower = oncoming = None
    for k in range(4):  # a follower 20 m behind closing at 2 m/s; an oncoming vehicle 200 m ahead closing at 14
        sweep = (Reading(Lane.LEFT, 1, -20.0 + 0.2 * k), Reading(Lane.LEFT, 2, -60.0), Reading(Lane.LEFT, 3, 30.0),
                 Reading(Lane.RIGHT, 4, 200.0 - 1.4 * k), Reading(Lane.RIGHT, 5, -10.0))
        follower = Nearest.after(follower, sweep, 10.0, behind=True)
        oncoming = Nearest.after(oncoming, sweep, 10.0, Lane.RIGHT)
    assert follower is not None and follower.dx_m == pytest.approx(19.4)
    assert follower.measured_mps == pytest.approx(2.0)
    assert oncoming is not None and oncoming.dx_m == pytest.approx(195.8)
    assert oncoming.measured_mps == pytest.approx(14.0)
