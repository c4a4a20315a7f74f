"""Toes kept out of the floor for feet the positions did not orient
(:func:`~expressive_mocap.skeletons.planting.toes_above`), on the procedural walk (no data needed)."""

from __future__ import annotations

import numpy as np

from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.planting import toes_above

UP = np.array([0.0, 1.0, 0.0])


def test_toes_below_the_level_are_lifted_and_nothing_else_moves():
    walk = procedural_walk(seconds=2.0)
    jmap = find_joint_map(walk.skeleton)
    before = walk.positions()
    toes = [jmap["left_toes"], jmap["right_toes"]]
    level = float(before[:, toes, 1].min()) + 1.5  # 1.5 cm above where the toes stand
    assert (before[:, toes, 1] < level).mean() > 0.3
    lifted = toes_above(walk, jmap, UP, level)
    after = lifted.positions()
    assert after[:, toes, 1].min() >= level - 1e-6
    others = [j for j in range(walk.skeleton.n_joints) if j not in toes]
    assert np.allclose(after[:, others], before[:, others], atol=1e-9)  # ankles and all but the toes stay
    above = before[:, toes, 1] >= level
    assert np.allclose(after[:, toes][above], before[:, toes][above], atol=1e-9)  # toes above: untouched
    lengths = [
        np.linalg.norm(p[:, toes] - p[:, [jmap["left_foot"], jmap["right_foot"]]], axis=-1) for p in (before, after)
    ]
    assert np.allclose(*lengths)
    turned = np.degrees(quat.angle(quat.mul(quat.conjugate(walk.rotations), lifted.rotations)))
    feet = [jmap["left_foot"], jmap["right_foot"]]
    assert turned[:, feet].max() > 1.0 and np.delete(turned, feet, axis=1).max() < 1e-6  # only the feet turned
