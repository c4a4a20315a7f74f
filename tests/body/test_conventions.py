"""Conventions of any humanoid skeleton, on ground truth: the demo's walk written on synthetic
skeletons built after six conventions (Bandai, CMU, Mixamo, SMPL, a game rig, LAFAN1). The
package must read each one's up and facing axes, unit, rest pose and frame rate from the data,
and take a motion to the canonical axes and back."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body import conventions as conv
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.skeletons.synthetic import RIGS, synthetic_walk


@pytest.fixture(scope="module")
def walks() -> dict[str, em.Motion]:
    return {rig: synthetic_walk(rig, wave="right").motion for rig in RIGS}


@pytest.mark.parametrize("rig", RIGS)
def test_conventions_are_read_from_the_data(walks, rig):
    built = synthetic_walk(rig).conventions
    read = conv.read_conventions(walks[rig], find_joint_map(walks[rig].skeleton))
    assert (read.up, read.facing, read.unit, read.rest_pose) == (built.up, built.facing, built.unit, built.rest_pose)
    assert read.fps == pytest.approx(built.fps)
    assert read.height * read.metres_per_unit == pytest.approx(1.63, abs=0.05)  # the Bandai actor's legs
    assert min(read.sure.values()) > 0.4


def test_unknown_units_scale_to_a_typical_actor_and_overrides_win(walks):
    motion = walks["lafan"].scaled(1 / 12)  # a unit of 12 cm: a 13-unit actor in no unit we know
    jmap = find_joint_map(motion.skeleton)
    read = conv.read_conventions(motion, jmap)
    assert read.unit == "unknown" and read.metres_per_unit * read.height == pytest.approx(1.70)
    given = read.with_overrides(up="z", facing="-y", unit="in")
    assert (given.up, given.facing, given.unit, given.metres_per_unit) == ("+Z", "-Y", "in", 0.0254)
    with pytest.raises(em.MocapError, match="must be horizontal"):
        read.with_overrides(up="Y", facing="-Y")


@pytest.mark.parametrize("rig", ["smpl", "game", "cmu"])
def test_to_canonical_and_back_is_the_identity(walks, rig):
    motion = walks[rig]
    read = conv.read_conventions(motion, find_joint_map(motion.skeleton))
    canonical = conv.to_canonical(motion, read)
    hips = canonical.positions()[:, find_joint_map(motion.skeleton)["hips"]]
    assert np.median(hips[:, 1]) == pytest.approx(0.90, abs=0.03)  # Y up, metres
    assert hips[-1, 2] - hips[0, 2] > 3.0  # walking towards +Z (1.2 m/s for 4 s, carried over)
    back = conv.from_canonical(canonical, read)
    np.testing.assert_allclose(back.positions(), motion.positions(), atol=1e-9 / read.metres_per_unit)
