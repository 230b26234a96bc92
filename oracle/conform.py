"""Agreement between engines' answers: what "the engines agree plan for plan" means, in one place."""

from __future__ import annotations

from spec.actions import plan_text
from spec.answers import Answer, Status, Strategy

#: The plan-free answers; they agree with each other on "no plan within the horizon".
NO_PLAN = (Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON)


def disagreement(a: Answer, b: Answer) -> str | None:
    """Why two answers for the same scenario and strategy disagree, or None.

    Both must find a plan or both none; plans must come from the same model; for
    ``sensible`` the action lists must be identical, for ``shortest`` the lengths equal.
    "No plan of any length" from one engine and "none within the horizon" from another
    agree (the second is the weaker claim). An incomplete answer is compared with nothing.
    """
    if Status.INCOMPLETE in (a.status, b.status):
        return None
    if (a.status is Status.PLAN) != (b.status is Status.PLAN):
        return f"{a.engine} says {a.status.value}, {b.engine} says {b.status.value}"
    if a.status is not Status.PLAN:
        return None
    if a.model is not b.model:
        return f"{a.engine} plans with the {_name(a)} model, {b.engine} with the {_name(b)} model"
    strategy = a.strategy if a.strategy is b.strategy else None
    if strategy is Strategy.SENSIBLE and a.actions != b.actions:
        return f"sensible plans differ: {a.engine} {_plan(a)} vs {b.engine} {_plan(b)}"
    if strategy is Strategy.SHORTEST and len(a.actions) != len(b.actions):
        return f"shortest lengths differ: {a.engine} {len(a.actions)} vs {b.engine} {len(b.actions)}"
    return None


def disagreements(answers: list[Answer]) -> list[str]:
    """Every disagreement of an answer with the first one (the reference engine's)."""
    return [d for other in answers[1:] if (d := disagreement(answers[0], other)) is not None]


def _name(answer: Answer) -> str:
    return answer.model.value if answer.model else "-"


def _plan(answer: Answer) -> str:
    return plan_text(answer.actions)
