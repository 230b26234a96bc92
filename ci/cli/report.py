"""The report command: campaign output folders as one HTML page a person reads, and Markdown for a CI summary."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

import click

from ci.cli.common import err, out, print_paths
from ci.shared.options import FRAMED, out_file
from spec.errors import OptionError

DEFAULT_TITLE = "overtake: conformance, simulation and audit"
MAX_TITLE = 200


def _write(option: str, path: Path, content: str | bytes) -> None:
    """``content`` into ``path`` whole or not at all (a temporary file renamed over it)."""
    data = content.encode("utf-8") if isinstance(content, str) else content
    temporary: str | None = None
    try:
        with tempfile.NamedTemporaryFile("wb", dir=path.parent, prefix=f".{path.name}.", delete=False) as tmp:
            temporary = tmp.name
            tmp.write(data)
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(temporary, 0o666 & ~mask)  # as an ordinary file would be made, not the temporary file's 0600
        os.replace(temporary, path)
    except OSError as error:
        if temporary is not None:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
        raise OptionError(option, str(path), f"cannot be written ({error.strerror or error})") from None


@click.command()
@click.argument("folders", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "out_path", default="report.html", show_default=True,
              help="The HTML page (self-contained: opens from disk with no network).")
@click.option("--markdown", "markdown_path", default=None,
              help="Also the tables and findings as Markdown (for a CI job summary; images linked, drawings beside "
                   "it in NAME-drawings/). Default: none.")
@click.option("--title", default=DEFAULT_TITLE, show_default=True)
@click.option("--frames", type=FRAMED, default=3, show_default=True,
              help="Closest calls per simulate or audit folder drawn with PyBullet's camera (each replays its drive "
                   "from the seed up to the event); 0: none.")
def report(folders: tuple[Path, ...], out_path: str, markdown_path: str | None, title: str, frames: int) -> None:
    """Turn the output folders of crossval, simulate, audit and the mutation check into one report.

    Each FOLDER is a campaign's --out, or a folder holding them one level down (e.g. `out`). Exit 0 when
    something was read; 2 on a missing folder, an unwritable output, or nothing to read."""
    from ci.report.collect import collect
    from ci.report.render import to_html, to_markdown

    if not title.strip() or not title.isprintable() or len(title) > MAX_TITLE:
        raise OptionError("--title", title, f"must be one printable line of 1 to {MAX_TITLE} characters")
    for folder in folders:
        if not folder.is_dir():
            raise OptionError("FOLDER", str(folder), "no such folder" if not folder.exists() else "not a folder")
        if not os.access(folder, os.R_OK | os.X_OK):
            raise OptionError("FOLDER", str(folder), "cannot be read")
    html_file = out_file("--out", out_path)
    md_file = out_file("--markdown", markdown_path) if markdown_path else None
    made = collect(folders, frames)
    if not made.sections:
        why = "; ".join(f"{folder}: {reason}" for folder, reason in made.skipped)
        raise OptionError("FOLDER", " ".join(map(str, folders)), f"no campaign output to report on ({why})")
    for skipped, reason in made.skipped:
        err.print(f"report: skipped {skipped}: {reason}")
    _write("--out", html_file, to_html(made, title))
    written = [html_file]
    if md_file is not None:
        text, drawings = to_markdown(made, title, md_file)
        for path, drawn in drawings.items():
            try:
                path.parent.mkdir(exist_ok=True)
            except OSError as error:
                raise OptionError("--markdown", str(path.parent), f"cannot be made ({error.strerror})") from None
            _write("--markdown", path, drawn)
        _write("--markdown", md_file, text)
        written.append(md_file)
    for finding in made.headline.findings:
        out.print(f"- {finding}")
    print_paths(f"read {len(made.found)} campaign folder(s), skipped {len(made.skipped)}; wrote:", written)


COMMANDS = (report,)
