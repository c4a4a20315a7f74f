"""render's options as keywords: ``poses`` for a PNG, ``speed`` for a GIF, each checked."""

import pytest

from expressive_mocap.errors import ArgumentError, MocapError
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.viz.render import render


@pytest.fixture(scope="module")
def walk():
    return procedural_walk(seconds=0.4)


def test_each_output_takes_its_own_option(walk, tmp_path):
    assert render([walk], tmp_path / "walk.png", poses=3, speed=2.0) is None  # speed is the GIF's
    played = render([walk], tmp_path / "walk.gif", ["walk"], "front", poses=3, speed=2.0)  # poses the PNG's
    assert played is not None and "(asked 2)" in played
    assert (tmp_path / "walk.png").stat().st_size > 0 and (tmp_path / "walk.gif").stat().st_size > 0


@pytest.mark.parametrize("poses", [0, -2, 2.5, "4", True])
def test_a_bad_number_of_poses_names_the_argument(walk, tmp_path, poses):
    with pytest.raises(ArgumentError, match="^argument `poses`: expected a whole number of poses >= 1"):
        render([walk], tmp_path / "walk.png", poses=poses)
    assert not (tmp_path / "walk.png").exists()


def test_a_bad_speed_or_view_is_refused(walk, tmp_path):
    with pytest.raises(MocapError, match="speed must be a positive number"):
        render([walk], tmp_path / "walk.gif", speed=0.0)
    with pytest.raises(MocapError, match="view must be one of side, front"):
        render([walk], tmp_path / "walk.png", view="top")  # type: ignore[arg-type]
