"""What a report holds, whatever it is printed as: findings, tables, figures and drawings, per section."""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rich.table import Table as RichTable

from sim.report import pyplot


@dataclass(frozen=True, slots=True)
class Table:
    """A table as text: a title, the column headers and the rows (every row as many cells as headers)."""

    title: str
    headers: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]
    note: str = ""

    def __post_init__(self) -> None:
        for row in self.rows:
            if len(row) != len(self.headers):
                raise ValueError(f"table {self.title!r}: a row of {len(row)} cells under {len(self.headers)} headers")


@dataclass(frozen=True, slots=True)
class Figure:
    """A PNG image: a file on disk, or made for the report (``data``, written beside the Markdown as ``name``);
    embedded in the HTML page, linked from the Markdown."""

    path: Path | None
    caption: str
    data: bytes | None = None
    name: str = ""  # a file stem, unique within one report, for an image made here

    def png(self) -> bytes:
        if self.data is not None:
            return self.data
        assert self.path is not None
        return self.path.read_bytes()


def png_bytes(fig: Any) -> bytes:
    """A matplotlib figure as the PNG bytes of a ``Figure`` (80 dpi, cropped to what is drawn); the figure is closed."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=80, bbox_inches="tight")
    pyplot().close(fig)
    return buffer.getvalue()


@dataclass(frozen=True, slots=True)
class Drawing:
    """An SVG made for the report (inline in the HTML page; a file beside the Markdown)."""

    name: str  # a file stem: unique within one report
    svg: str
    caption: str


@dataclass(slots=True)
class Section:
    """One part of the report: one campaign folder, or the headline over all of them."""

    key: str  # the HTML anchor: unique within one report
    title: str
    source: str  # the folder it was read from ("" for the headline)
    findings: list[str] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    drawings: list[Drawing] = field(default_factory=list)
    texts: list[tuple[str, str]] = field(default_factory=list)  # (caption, preformatted text)
    facts: dict[str, Any] = field(default_factory=dict)  # the figures the headline adds up over sections


@dataclass(slots=True)
class Report:
    """The whole page: the headline (what a reader wants first), the sections, what was read and what skipped."""

    headline: Section
    sections: list[Section]
    found: list[tuple[str, str]]  # (folder, what it holds)
    skipped: list[tuple[str, str]]  # (folder or file, why it was not read)


def from_rich(table: RichTable) -> Table:
    """A rich table (the terminal's) as this report's table: the same title, headers and cells, as text."""
    columns = table.columns
    headers = tuple(str(c.header) if table.show_header else "" for c in columns)
    cells = [[str(cell) for cell in c.cells] for c in columns]
    rows = tuple(tuple(col[i] for col in cells) for i in range(table.row_count))
    return Table(str(table.title or ""), headers, rows)
