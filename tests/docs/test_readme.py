"""The README is a short front page: it says what the package does and opens with its two commands,
the second of which (`make check`, the Makefile's checks in order) is what CI runs (keep them from
drifting apart); it links every page of the manual in docs/, whose links lead somewhere."""

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
# The Makefile's checks, in the order `make check` runs them.
CHECKS = ["setup", "lint", "types", "rust", "test", "test-numpy2"]


def readme_commands() -> list[str]:
    text = (REPO / "README.md").read_text()
    block = text.split("```sh\n", 1)[1].split("```", 1)[0]
    return [line for line in block.splitlines() if line.strip()]


def test_readme_opens_with_two_commands_and_ci_runs_the_test_one():
    demo, tests = readme_commands()
    assert demo == "pip install . && expressive-mocap demo"
    assert tests == "make check"
    ci = [
        line
        for line in (REPO / ".ci" / "run").read_text().splitlines()
        if line and not line.startswith(("#", "set ", "cd "))
    ]
    assert ci == [tests]


def test_the_readme_says_what_the_package_does_and_how_to_start_in_its_first_20_lines():
    head = (REPO / "README.md").read_text().splitlines()[:20]
    before = head[: head.index("```sh")]
    prose = " ".join(line for line in before if line.strip() and not line.startswith("#"))
    assert "motion capture" in prose, "say what the package does, in a sentence before the commands"
    assert sum(line.startswith("```") for line in head) >= 2, "the two commands, whole, within the first 20 lines"


def makefile_rules() -> dict[str, list[str]]:
    """Each rule's target and its prerequisites, in order."""
    text = (REPO / "Makefile").read_text()
    return {m[1]: m[2].split() for m in re.finditer(r"^([\w.-]+):(?!=)(.*)$", text, re.M)}


def test_make_check_runs_every_check_in_order_and_every_target_is_phony():
    rules = makefile_rules()
    assert rules["check"] == CHECKS
    assert set(CHECKS) | {"check"} <= set(rules[".PHONY"])
    assert ".NOTPARALLEL" in rules, "the checks run one after the other, even under make -j"


def make_dry_run(target: str) -> str:
    if shutil.which("make") is None:
        pytest.skip("no make here")
    env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}
    return subprocess.run(["make", "-n", target], cwd=REPO, env=env, capture_output=True, text=True, check=True).stdout


def test_the_checks_run_the_tests_and_lint_the_python_folders_ruff_is_set_for():
    if sys.version_info >= (3, 11):
        import tomllib
    else:
        tomllib = pytest.importorskip("tomli")
    src = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["ruff"]["src"]
    folders = [f for f in src if (REPO / f).is_dir()]
    commands = make_dry_run("check").splitlines()
    for tool in ("ruff check", "ruff format --check"):
        [line] = [c for c in commands if c.startswith(tool + " ")]
        assert set(folders) <= set(line.split()[len(tool.split()) :]), (line, folders)
    for needed in (
        "pip install '.[test]'",
        "cargo fmt --check",
        "cargo clippy -q -- -D warnings",
        "cargo clippy -q --features python -- -D warnings",
        "mypy",
        "python -m mypy.stubtest expressive_mocap._core",
        "cargo test --release -q",
        "python -m pytest -m 'not torch'",
        ".venv-numpy2/bin/python -m pytest -m 'not blender'",
    ):
        assert needed in commands, needed


def test_readme_is_a_front_page_linking_every_page_of_the_manual():
    text = (REPO / "README.md").read_text()
    assert len(text.encode()) < 8192, "the README is the front page: the manual goes in docs/"
    pages = sorted(p.name for p in (REPO / "docs").glob("*.md"))
    assert pages and all(f"](docs/{page})" in text for page in pages), pages


def anchors(markdown: str) -> set[str]:
    """The anchors GitHub gives a page's headings (lower case, punctuation dropped, spaces as -)."""
    text = re.sub(r"```.*?```", "", markdown, flags=re.S)
    return {re.sub(r"[^\w\- ]", "", h.strip().lower()).replace(" ", "-") for h in re.findall(r"^#+ (.*)$", text, re.M)}


def test_the_pages_relative_links_lead_to_files_and_headings_that_exist():
    for page in [REPO / "README.md", *sorted((REPO / "docs").glob("*.md"))]:
        for target, anchor in re.findall(r"\]\(([^)#:\s]*)(?:#([^)]*))?\)", page.read_text()):
            path = page.parent / target if target else page
            assert path.exists(), f"{page.name}: {target}"
            if anchor and path.suffix == ".md":
                assert anchor in anchors(path.read_text()), f"{page.name}: {target}#{anchor}"
