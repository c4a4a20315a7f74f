"""Fixtures of the dataset tests."""

from __future__ import annotations

from pathlib import Path

import pytest

from mixed_archives import bandai_members, cmu_members, zip_of


@pytest.fixture(scope="module")
def mixed_zip(bandai2_dir, other_dir, tmp_path_factory) -> tuple[Path, dict[str, Path]]:
    """3 Bandai clips at 30 fps and 2 CMU clips at 120 fps, the CMU clips first by name."""
    members = {**bandai_members(bandai2_dir), **cmu_members(other_dir)}
    return zip_of(tmp_path_factory.mktemp("mixed") / "mixed.zip", members), members
