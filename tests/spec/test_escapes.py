"""The escapes' registry checks itself, the commitment semantics' options and file keys are checked and round-trip,
and an unsafe start names the lane's first escape."""

from __future__ import annotations

from dataclasses import replace

import pytest

from spec.actions import ACTION_RULES, Action
from spec.envelope import MINIMAL_RISK
from spec.errors import OptionError
from spec.escapes import (
    COMMIT,
    ESCAPES,
    Commitment,
    Escape,
    EscapeKind,
    MoveWay,
    check_escapes,
    move_ways,
    parse_escape_kinds,
    parse_most_actions,
    unsafe_start_escape,
)
from spec.lanes import Lane
from spec.physical import LOOP
from spec.sound import sound_from, sound_from_table, sound_to_table


def test_every_escape_ends_in_the_left_lane_from_its_own_lane() -> None:
    for e in ESCAPES:
        lane = e.from_lane
        for a in e.actions:
            assert ACTION_RULES[a].from_lane in (None, lane)
            lane = ACTION_RULES[a].to_lane or lane
        assert lane is Lane.LEFT, e
    assert {e.kind for e in ESCAPES} == set(EscapeKind)
    assert {e.from_lane for e in ESCAPES} == set(Lane)


@pytest.mark.parametrize(("bad", "why"), [
    (Escape(EscapeKind.ABORT, Lane.RIGHT, (Action.BRAKE,), "stays in the right lane"), "ends in the right lane"),
    (Escape(EscapeKind.ABORT, Lane.LEFT, (Action.LEFT_LANE_CHANGE,), "from the wrong lane"), "not enabled"),
    (Escape(EscapeKind.MINIMAL_RISK, Lane.RIGHT, (Action.LEFT_LANE_CHANGE,), "a manoeuvre"), "stays in the left"),
    (Escape(EscapeKind.MINIMAL_RISK, Lane.LEFT, (Action.ACCELERATE,), "faster"), "never faster"),
    (Escape(EscapeKind.ABORT, Lane.LEFT, (), "nothing"), "only the minimal-risk"),
    (Escape(EscapeKind.ABORT, Lane.RIGHT, (Action.ACCELERATE, Action.LEFT_LANE_CHANGE), "speeds up"), "speeds up"),
    (ESCAPES[3], "the same manoeuvre"),
])
def test_the_registry_refuses_an_escape_that_cannot_be_one(bad: Escape, why: str) -> None:
    with pytest.raises(ValueError, match=why):
        check_escapes((*ESCAPES, bad))


def test_an_unsafe_start_takes_the_lanes_first_escape() -> None:
    assert unsafe_start_escape(Lane.LEFT).kind is EscapeKind.MINIMAL_RISK and not unsafe_start_escape(Lane.LEFT).actions
    assert unsafe_start_escape(Lane.RIGHT).actions == (Action.LEFT_LANE_CHANGE,)


def test_a_commitment_allows_its_escapes_in_the_registrys_order() -> None:
    only_abort = Commitment(escapes=(EscapeKind.ABORT,))
    assert [e.kind for e in only_abort.allowed(Lane.RIGHT)] == [EscapeKind.ABORT, EscapeKind.ABORT]
    assert only_abort.allowed(Lane.LEFT) == ()
    assert COMMIT.allowed(Lane.LEFT) == tuple(e for e in ESCAPES if e.kind is EscapeKind.MINIMAL_RISK)


@pytest.mark.parametrize("value", [0, -1, 201, "1.5", "many", True, 2.5])
def test_a_commitment_of_no_action_or_beyond_the_horizon_is_bad_input(value: object) -> None:
    with pytest.raises(OptionError, match="--commit-max"):
        parse_most_actions(value, "--commit-max")


@pytest.mark.parametrize("value", ["teleport", "abort,abort", "", ",", [], ["abort", 3]])
def test_unknown_repeated_or_no_escapes_are_bad_input(value: object) -> None:
    with pytest.raises(OptionError, match="--escapes"):
        parse_escape_kinds(value, "--escapes")


def test_the_command_line_and_files_default_to_the_commitment_semantics_and_round_trip() -> None:
    plain = sound_from(None, "default")
    assert plain.commitment == COMMIT
    whole = sound_from(None, "default", semantics="whole")
    assert whole.commitment is None
    tight = sound_from(None, "default", commit_max=1, escapes="complete,abort")
    assert tight.commitment == Commitment(1, (EscapeKind.ABORT, EscapeKind.COMPLETE))
    for model in (plain, whole, tight):
        assert sound_from_table(sound_to_table(model)) == model
    assert "semantics" not in sound_to_table(plain) and sound_to_table(whole)["semantics"] == "whole"
    assert sound_from(whole, None, commit_max=2).commitment == Commitment(2)  # asking for a commitment turns it on
    assert sound_from(tight, None).commitment == tight.commitment  # a file's semantics stays unless changed


def test_a_commitment_option_with_whole_plans_names_the_option() -> None:
    with pytest.raises(OptionError, match=r"--escapes.*whole plans"):
        sound_from(None, "default", semantics="whole", escapes="abort")
    with pytest.raises(OptionError, match=r"bounds\.commit_max"):
        sound_from_table({"semantics": "whole", "commit_max": 2})
    assert replace(sound_from(None, "paper"), commitment=None) == sound_from(None, "paper", semantics="whole")


@pytest.mark.parametrize("to_lane", list(Lane))
def test_a_move_under_way_is_finished_first_and_undone_only_within_its_first_quarter(to_lane: Lane) -> None:
    """``move_ways``: finishing (the lane it goes to, what is left of the move), then undoing (the lane it left, as
    long as the move has taken) up to ``MinimalRisk.reverse_within_s`` and not a control step after."""
    within = MINIMAL_RISK.reverse_within_s
    back = Lane.LEFT if to_lane is Lane.RIGHT else Lane.RIGHT
    assert move_ways(to_lane, within, 2.0 - within) == ((MoveWay.FINISH, to_lane, 2.0 - within),
                                                        (MoveWay.UNDO, back, within))
    late = within + LOOP.physics_dt_s * LOOP.control_every_steps
    assert move_ways(to_lane, late, 2.0 - late) == ((MoveWay.FINISH, to_lane, 2.0 - late),)
