"""benches/RESULTS.md holds one section per benchmark; a script that writes it rewrites only its own.

    from results import write_section
    write_section("Whole-archive read and FK", text)   # replaces "## Whole-archive read and FK" and its body

A section is its heading line and everything after it up to the next heading of the same or a
higher level (so its own ``###`` subsections go with it, the next ``##`` section stays). A section
that is not there yet is appended at the end. Headings inside fenced code blocks do not count.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

__all__ = ["RESULTS", "write_section", "replace_section"]

RESULTS = Path(__file__).resolve().parent / "RESULTS.md"
HEADING = re.compile(r"^(#{1,6}) +(.*?)\s*$")


def _headings(lines: list[str]) -> list[tuple[int, int, str]]:
    """(line index, level, title) of every Markdown heading outside fenced code blocks."""
    found, fenced = [], False
    for i, line in enumerate(lines):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        match = None if fenced else HEADING.match(line)
        if match:
            found.append((i, len(match[1]), match[2]))
    return found


def replace_section(document: str, title: str, text: str, level: int = 2) -> str:
    """``document`` with the section headed ``title`` at ``level`` replaced by ``text`` (its body,
    without the heading), or with that section appended when absent."""
    body = text.strip("\n")
    section = [f"{'#' * level} {title}", "", *([body] if body else [])]
    lines = document.splitlines()
    headings = _headings(lines)
    start = next((i for i, lv, t in headings if lv == level and t == title.strip()), None)
    if start is None:
        kept = document.rstrip("\n")
        return (kept + "\n\n" if kept else "") + "\n".join(section) + "\n"
    end = next((i for i, lv, _ in headings if i > start and lv <= level), len(lines))
    after = lines[end:]
    return "\n".join(lines[:start] + section + ([""] if after else []) + after) + "\n"


def write_section(title: str, text: str, path: str | os.PathLike = RESULTS, level: int = 2) -> Path:
    """Rewrite the section ``title`` of ``path`` (benches/RESULTS.md by default) with ``text``,
    keeping every other section; the file is replaced atomically (a complete file or the old one)."""
    path = Path(path)
    old = path.read_text(encoding="utf-8") if path.exists() else ""
    new = replace_section(old, title, text, level)
    fd, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as out:
            out.write(new)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
    return path
