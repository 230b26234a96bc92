"""The closest calls of a campaign, seen: every collision first, then the near misses with the smallest true gap, each
replayed from its seed and configuration (``sim.frames``) and drawn as a strip of PyBullet camera frames of the
seconds before it, beside what the AV was doing and what the attribution said."""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path
from typing import Any

from ci.report.document import Figure, png_bytes
from ci.shared.records import read_records
from sim.report import pyplot

FRAMES, BEFORE_S = 4, 3.0


def gap_order(encounter: dict[str, Any]) -> tuple[bool, bool, float]:
    """Collisions first, then by true gap (a gap not recorded, or not a number: last)."""
    gap = encounter.get("gap_m")
    known = isinstance(gap, (int, float)) and not isinstance(gap, bool)
    return encounter.get("kind") != "contact", not known, float(gap) if known else 0.0  # type: ignore[arg-type]


def events(records: Iterable[dict[str, Any]]) -> list[tuple[dict[str, Any], int, dict[str, Any]]]:
    """(drive configuration, seed, encounter) of every contact and near miss in ``records`` (a simulate or audit
    campaign's JSON lines), collisions first, then by true gap."""
    found = []
    for record in records:
        try:
            config, run = record["campaign"], record["run"]
            found += [(config, int(run["seed"]), e) for e in run["safety"]["encounters"] if isinstance(e, dict)]
        except (KeyError, TypeError, ValueError):
            continue
    return sorted(found, key=lambda e: gap_order(e[2]))


def closest_figures(log: Path, limit: int, key: str) -> tuple[list[Figure], list[str]]:
    """Figures of the first ``limit`` events in the campaign file ``log``, and a line per event not drawn (why)."""
    from sim.frames import replay_frames
    from sim.parts import DriveConfig

    figures, notes = [], []
    for n, (config_json, seed, e) in enumerate(events(read_records(log))[:limit], 1):
        described = config_json if isinstance(config_json, dict) else {}
        what = (f"{e.get('kind', '?')} at {e.get('km', '?')} km (t = {e.get('t_s', '?')} s), seed {seed}, "
                f"{described.get('model', 'paper')} model, {described.get('traffic')} traffic, "
                f"{described.get('sensor')} sensing, {described.get('cell_m')} m cells")
        try:
            if not isinstance(config_json, dict):
                raise TypeError(f"a configuration of {type(config_json).__name__}")
            config = DriveConfig.from_json(config_json)
            replay = replay_frames(seed, config, float(e["t_s"]), str(e.get("kind")), FRAMES, BEFORE_S)
        except Exception as error:  # the frames are an extra: any failure of a replay is said, never the report's end
            notes.append(f"{what}: not replayed ({type(error).__name__}: {error})")
            continue
        if not replay.frames:
            notes.append(f"{what}: the replay ended before it (the code has changed since the campaign)")
            continue
        met = ("replayed from the seed" if replay.met else "NOT met again by the replay from the seed (the code has "
               "changed since the campaign): the frames show the same seconds of the replay")
        caption = (f"{what}: {e.get('doing', '')}; true gap {e.get('gap_m')} m; {e.get('assumptions') or ''} "
                   f"({met}; the AV green, same-direction vehicles blue, oncoming red)")
        figures.append(Figure(None, caption, _strip(replay.frames), f"{key}-closest-{n}"))
    return figures, notes


def _strip(frames: list[Any]) -> bytes:
    """The frames side by side, each titled with its time, as PNG bytes."""
    fig, axes = pyplot().subplots(1, len(frames), figsize=(3.2 * len(frames), 1.9))
    for axis, frame in zip(axes if len(frames) > 1 else [axes], frames):
        axis.imshow(frame.image)
        axis.set_title(f"t = {frame.t_s:.1f} s", fontsize=9)
        axis.axis("off")
    return png_bytes(fig)
