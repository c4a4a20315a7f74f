"""The Python versions the package claims: every module parses with the oldest one's grammar
(CI has only CPython 3.11 to run on), and the claims in pyproject.toml agree with each other."""

import ast
import re
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PYPROJECT = (REPO / "pyproject.toml").read_text()


def claimed_versions() -> list[tuple[int, int]]:
    return [(3, int(minor)) for minor in re.findall(r'"Programming Language :: Python :: 3\.(\d+)"', PYPROJECT)]


def test_requires_python_is_the_oldest_listed_version():
    oldest = re.search(r'requires-python = ">=3\.(\d+)"', PYPROJECT)
    assert oldest and (3, int(oldest.group(1))) == min(claimed_versions())
    assert sys.version_info[:2] in claimed_versions()


@pytest.mark.parametrize("path", sorted((REPO / "python" / "expressive_mocap").rglob("*.py")), ids=lambda p: p.name)
def test_the_package_parses_with_the_oldest_claimed_grammar(path):
    # e.g. a match statement or parenthesised context managers would fail here on 3.9.
    ast.parse(path.read_text(), filename=str(path), feature_version=min(claimed_versions()))
