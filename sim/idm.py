"""The Intelligent Driver Model (Treiber, Hennecke and Helbing 2000): one car's acceleration behind its leader."""

from __future__ import annotations

import math

from spec.physical import IDM, IdmSpec


def idm_accel_mps2(speed_mps: float, desired_mps: float, gap_m: float, closing_mps: float,
                   spec: IdmSpec = IDM) -> float:
    """The acceleration of a car at ``speed_mps`` wishing to drive at ``desired_mps``, ``gap_m`` bumper to bumper
    behind its leader (``math.inf``: none) and closing on it at ``closing_mps`` (negative: falling back).

    a (1 - (v / v0)^delta - (s* / s)^2), s* = s0 + max(0, v T + v dv / (2 sqrt(a b))), bounded below by
    ``max_decel_mps2``.
    """
    free = 1.0 - (speed_mps / desired_mps) ** spec.exponent if desired_mps > 0 else -math.inf
    interaction = 0.0
    if math.isfinite(gap_m):
        wanted = spec.min_gap_m + max(0.0, speed_mps * spec.time_gap_s + speed_mps * closing_mps
                                      / (2 * math.sqrt(spec.accel_mps2 * spec.comfortable_decel_mps2)))
        interaction = (wanted / max(gap_m, 0.01)) ** 2
    return max(-spec.max_decel_mps2, spec.accel_mps2 * (free - interaction))
