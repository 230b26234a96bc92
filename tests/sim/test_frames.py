"""sim/frames.py: a drive replayed from its seed meets its own events again, and its frames show the road."""

from __future__ import annotations

import numpy as np

from sim.frames import AV_RGBA, replay_frames
from sim.parts import DriveConfig
from sim.simulator import run_drive

#: IDM traffic at 21 m cells: the paper model collides within a kilometre on this seed (the audit's CI seed of a day).
CONFIG = DriveConfig(1.0, traffic="following", restart_after_collision=True)
SEED = 20261126


def test_a_replay_meets_the_drives_own_event_and_draws_the_seconds_before_it() -> None:
    summary = run_drive(SEED, CONFIG)
    assert summary.safety.encounters, "the drive this test replays has no event any more: pick another seed"
    event = summary.safety.encounters[0]
    replay = replay_frames(SEED, CONFIG, event.t_s, event.kind, count=3, before_s=2.0)
    assert replay.met
    assert [round(f.t_s, 1) for f in replay.frames] == [round(event.t_s - 2.0 + i, 1) for i in range(3)]
    for frame in replay.frames:
        assert frame.image.shape == (240, 480, 3) and frame.image.std() > 10  # a picture, not one colour
        green = np.array(AV_RGBA[:3]) * 255
        assert (np.abs(frame.image.astype(float) - green).sum(axis=2) < 120).any()  # the AV is in it


def test_a_replay_draws_across_the_restart_after_a_collision() -> None:
    """The audit restarts a drive in a fresh scene after a collision: frames on both sides of it are drawn."""
    contact = next(e for e in run_drive(SEED, CONFIG).safety.encounters if e.kind == "contact")
    replay = replay_frames(SEED, CONFIG, contact.t_s + 2.0, "near_miss", count=2, before_s=3.0)
    assert len(replay.frames) == 2 and replay.frames[1].t_s > contact.t_s


def test_a_replay_says_when_it_does_not_meet_the_event() -> None:
    replay = replay_frames(SEED, CONFIG, 12.0, "contact", count=2, before_s=1.0)
    assert not replay.met and len(replay.frames) == 2
