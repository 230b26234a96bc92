"""A report as one self-contained HTML page (images embedded, no script, no request beyond the page) and as Markdown
for a CI job summary (images linked, drawings written beside it)."""

from __future__ import annotations

import base64
import os
import re
from html import escape
from pathlib import Path

from ci.report.document import Report, Section, Table

STYLE = """
body { font-family: sans-serif; margin: 2em auto; max-width: 1100px; padding: 0 1em; color: #222; }
section { margin-top: 2.5em; border-top: 1px solid #ccc; }
table { border-collapse: collapse; margin: 1em 0; font-size: 0.85em; }
caption { text-align: left; font-weight: bold; padding: 0.3em 0; }
th, td { border: 1px solid #ccc; padding: 0.2em 0.5em; text-align: left; vertical-align: top; }
th { background: #f0f0f0; }
figure { margin: 1em 0; }
figure img { max-width: 100%; border: 1px solid #ddd; }
pre { background: #f7f7f7; padding: 0.8em; overflow-x: auto; font-size: 0.8em; }
.source { color: #666; font-size: 0.9em; }
li { margin: 0.3em 0; }
"""


def to_html(report: Report, title: str) -> str:
    """The page: headline, what was read and skipped, then each section."""
    nav = "".join(f'<li><a href="#{s.key}">{escape(s.title)}</a> <span class="source">{escape(Path(s.source).name)}'
                  "</span></li>" for s in report.sections)
    body = [f"<h1>{escape(title)}</h1>", f"<nav><ul>{nav}</ul></nav>", _html_section(report.headline, 2)]
    read = "".join(f"<li>{escape(folder)}: {escape(kind)}</li>" for folder, kind in report.found)
    skipped = "".join(f"<li>{escape(folder)}: {escape(why)}</li>" for folder, why in report.skipped)
    body.append(f'<section id="inputs"><h2>What was read</h2><ul>{read or "<li>nothing</li>"}</ul>'
                + (f"<h3>Skipped</h3><ul>{skipped}</ul>" if skipped else "") + "</section>")
    body += [_html_section(s, 2) for s in report.sections]
    return ("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            f"<title>{escape(title)}</title><style>{STYLE}</style></head><body>\n"
            + "\n".join(body) + "\n</body></html>\n")


def _html_section(section: Section, level: int) -> str:
    parts = [f'<section id="{escape(section.key)}"><h{level}>{escape(section.title)}</h{level}>']
    if section.source:
        parts.append(f'<p class="source">from {escape(section.source)}</p>')
    if section.findings:
        parts.append("<ul>" + "".join(f"<li>{_finding(f, section.key == 'headline')}</li>" for f in section.findings)
                     + "</ul>")
    parts += [_html_table(t) for t in section.tables]
    for figure in section.figures:
        data = base64.b64encode(figure.png()).decode("ascii")
        parts.append(f'<figure><img src="data:image/png;base64,{data}" alt="{escape(figure.caption)}">'
                     f"<figcaption>{escape(figure.caption)}</figcaption></figure>")
    for drawing in section.drawings:
        parts.append(f"<figure>{drawing.svg}<figcaption>{escape(drawing.caption)}</figcaption></figure>")
    for caption, text in section.texts:
        parts.append(f"<details><summary>{escape(caption)}</summary><pre>{escape(text)}</pre></details>")
    return "".join(parts) + "</section>"


def _finding(text: str, asked: bool) -> str:
    """A finding as HTML; the headline's question (up to its "? ") in bold."""
    question, mark, answer = text.partition("? ")
    if asked and mark:
        return f"<strong>{escape(question)}?</strong> {escape(answer)}"
    return escape(text)


def _html_table(table: Table) -> str:
    head = "".join(f"<th>{escape(h)}</th>" for h in table.headers)
    rows = "".join("<tr>" + "".join(f"<td>{escape(c)}</td>" for c in row) + "</tr>" for row in table.rows)
    note = f"<p>{escape(table.note)}</p>" if table.note else ""
    return (f"<table><caption>{escape(table.title)}</caption><thead><tr>{head}</tr></thead>"
            f"<tbody>{rows}</tbody></table>{note}")


def to_markdown(report: Report, title: str, markdown_path: Path) -> tuple[str, dict[Path, str | bytes]]:
    """The Markdown, and the files to write beside it (path -> SVG text or PNG bytes); images are linked relative
    to it."""
    here = markdown_path.parent
    drawings_dir = markdown_path.with_name(markdown_path.stem + "-drawings")
    files: dict[Path, str | bytes] = {}
    lines = [f"# {title}", ""]
    for section in (report.headline, *report.sections):
        lines += [f"## {section.title}", ""]
        if section.source:
            lines += [f"From `{section.source}`.", ""]
        for finding in section.findings:
            question, mark, answer = finding.partition("? ")
            asked = section is report.headline and mark
            lines.append(f"- **{_md_cell(question)}?** {_md_cell(answer)}" if asked else f"- {_md_cell(finding)}")
        lines += [""] if section.findings else []
        for table in section.tables:
            lines += _md_table(table)
        for figure in section.figures:
            path = figure.path
            if path is None:
                path = drawings_dir / f"{figure.name}.png"
                files[path] = figure.png()
            lines += [f"![{_md_cell(figure.caption)}]({_relative(path, here)})", ""]
        for drawing in section.drawings:
            path = drawings_dir / f"{drawing.name}.svg"
            files[path] = drawing.svg
            lines += [f"![{_md_cell(drawing.caption)}]({_relative(path, here)})", ""]
        for caption, text in section.texts:
            fence = "`" * max(3, 1 + max((len(run) for run in re.findall(r"`+", text)), default=0))
            lines += [f"<details><summary>{escape(caption)}</summary>", "", fence, text.rstrip(), fence, "",
                      "</details>", ""]
    lines += ["## What was read", ""] + [f"- `{folder}`: {kind}" for folder, kind in report.found]
    if report.skipped:
        lines += ["", "Skipped:", ""] + [f"- `{folder}`: {why}" for folder, why in report.skipped]
    return "\n".join(lines) + "\n", files


def _relative(path: Path, here: Path) -> str:
    return Path(os.path.relpath(path.resolve(), here.resolve())).as_posix()


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _md_table(table: Table) -> list[str]:
    lines = [f"**{_md_cell(table.title)}**", ""] if table.title else []
    headers = [_md_cell(h) or " " for h in table.headers]
    lines += ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in table.rows]
    return lines + ([table.note] if table.note else []) + [""]
