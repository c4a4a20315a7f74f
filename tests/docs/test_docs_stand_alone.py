"""The repository stands alone: what it ships says the methods in its own words and cites the
papers, and never sends its reader to material outside it (the team's planning notes, its
internal tracker, the folder beside the checkout that holds them).

Tests may read the Bandai-Namco archives from ``../shared/data`` and the scripts that measure
(benchmarks, experiments, tools) may run its ``unpack`` script, so tests/ is not checked at all and
the scripts (``*.py`` of ``SCRIPTS``) only for the notes and the tracker. docs/data.md says once,
in its section on how tests find the data, where the archives are looked for.
"""

from __future__ import annotations

import re
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]

# Planning notes that live outside the repository, and the internal tracker ("issue 3",
# "issue #3", "the issue's targets", "this issue", "from the issue"). The notes' METHODS.md is
# matched in capitals only: docs/methods.md is the repository's own page on the methods.
PRIVATE = re.compile(
    r"(?-i:METHODS\.md)|(?-i:\bMETHODS\b)|PEERS\.md"
    r"|\bissues?\s*#?\d+"
    r"|\b(?:the|this|that|our)\s+issue\b"
    r"|\bissue's\b",
    re.IGNORECASE,
)
# The folder beside the checkout.
SHARED = re.compile(r"\.\./shared\b")
# Places outside tests/ and benches/*.py that may name it: (file, section heading) -> how many
# times. None: docs/data.md describes where the tests look without naming the folder.
SHARED_ALLOWED: dict[tuple[str, str], int] = {}
# Folders of scripts that read the data, by default from the folder beside the checkout.
SCRIPTS = ("benches/", "experiments/", "tools/")


def tracked_text_files() -> dict[str, str]:
    try:
        listed = subprocess.run(["git", "ls-files", "-z"], cwd=REPO, capture_output=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout (an sdist or an installed copy): nothing to list")
    files = {}
    for name in filter(None, listed.decode().split("\0")):
        if name.startswith("tests/"):
            continue
        try:
            files[name] = (REPO / name).read_text(encoding="utf-8")
        except (UnicodeDecodeError, FileNotFoundError, IsADirectoryError):
            continue  # pictures, model arrays; a file deleted but not yet committed
    return files


def section_of(text: str, offset: int) -> str:
    """The Markdown heading (``#`` to ``####``) above ``offset``, or "" before the first."""
    headings = [m for m in re.finditer(r"^#{1,4} .*$", text[:offset], re.MULTILINE)]
    return headings[-1].group(0).strip() if headings else ""


def line_of(text: str, offset: int) -> int:
    return text.count("\n", 0, offset) + 1


def test_nothing_outside_tests_points_at_the_planning_notes_or_the_tracker():
    found = [
        f"{name}:{line_of(text, m.start())}: {m.group(0)!r}"
        for name, text in tracked_text_files().items()
        for m in PRIVATE.finditer(text)
    ]
    assert not found, "say it in the project's own words (and cite the paper):\n" + "\n".join(found)


def test_the_folder_beside_the_checkout_is_named_only_where_the_docs_say_where_the_data_are():
    seen: dict[tuple[str, str], int] = {}
    found = []
    for name, text in tracked_text_files().items():
        if name.startswith(SCRIPTS) and name.endswith(".py"):
            continue  # the scripts read the data from there
        for m in SHARED.finditer(text):
            place = (name, section_of(text, m.start()) if name.endswith(".md") else "")
            seen[place] = seen.get(place, 0) + 1
            if seen[place] > SHARED_ALLOWED.get(place, 0):
                found.append(f"{name}:{line_of(text, m.start())} (section {place[1]!r})")
    assert not found, "only docs/data.md, once, may say where the archives are looked for:\n" + "\n".join(found)


def test_the_patterns_catch_what_they_are_for():
    for text in (
        "see METHODS.md part 2",
        "METHODS' single cycle",
        "in ../shared/PEERS.md",
        "Fuzzing (issue 6)",
        "Targets (from the issue)",
        "after this issue's first commit",
        "issue #3",
        "Against the issue's targets",
    ):
        assert PRIVATE.search(text), text
    for text in (
        "PyUntypedArrayMethods",
        "the methods leave open",
        "a known issue with pybvh",
        "no issues found",
        "[docs/methods.md](docs/methods.md)",
    ):
        assert not PRIVATE.search(text), text
    assert SHARED.search("`../shared/data/unpack`") and not SHARED.search("its cost is shared")
    assert section_of("# A\n## Data\ntext", 12) == "## Data"
