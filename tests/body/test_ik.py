"""Two-bone IK (expressive_mocap.body.ik): hand-checkable legs."""

import numpy as np
import pytest

from expressive_mocap.body.ik import REACH, two_bone_ik
from expressive_mocap.rotations import quat

THIGH = np.array([0.0, -40.0, 0.0])
SHIN = np.array([0.0, -38.0, 2.0])


def chain(upper, lower, root):
    knee = root + quat.rotate(upper, THIGH)
    return knee, knee + quat.rotate(lower, SHIN)


@pytest.fixture
def leg():
    rng = np.random.default_rng(0)
    F = 50
    upper = quat.normalize(np.array([0.0, 0.0, 0.0, 1.0]) + 0.2 * rng.normal(size=(F, 4)))
    lower = quat.mul(upper, quat.about("X", rng.uniform(10, 60, F)))  # a bent knee
    root = rng.normal(size=(F, 3)) * 5
    return upper, lower, root


def test_reachable_targets_are_reached_and_bones_keep_their_length(leg):
    upper, lower, root = leg
    rng = np.random.default_rng(1)
    direction = rng.normal(size=root.shape)
    target = root + direction / np.linalg.norm(direction, axis=1, keepdims=True) * rng.uniform(10, 75, (len(root), 1))
    new_upper, new_lower = two_bone_ik(root, upper, lower, THIGH, SHIN, target)
    np.testing.assert_allclose(np.linalg.norm(new_upper, axis=1), 1.0, atol=1e-12)
    knee, end = chain(new_upper, new_lower, root)
    np.testing.assert_allclose(end, target, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(knee - root, axis=1), 40.0, atol=1e-9)


def test_the_current_end_is_a_fixed_point(leg):
    upper, lower, root = leg
    _, end = chain(upper, lower, root)
    new_upper, new_lower = two_bone_ik(root, upper, lower, THIGH, SHIN, end)
    assert np.degrees(quat.angle(quat.mul(quat.conjugate(upper), new_upper))).max() < 1e-5
    assert np.degrees(quat.angle(quat.mul(quat.conjugate(lower), new_lower))).max() < 1e-5


@pytest.mark.parametrize("knee", [0.0, 0.3, 0.5])
def test_a_straight_leg_at_its_own_end_is_a_fixed_point(leg, knee, backend):
    """A leg straighter than REACH allows (``knee`` degrees from straight: a stance leg of real
    captures) was bent to REACH: a planting that asked each foot to stay where it was moved the
    knee by 0.56 cm."""
    upper, _, root = leg
    straight = np.degrees(np.arctan2(SHIN[2], -SHIN[1]))  # the knee turn that lines the shin up with the thigh
    lower = quat.mul(upper, quat.about("X", np.full(len(upper), straight + knee)))
    knee_before, end = chain(upper, lower, root)
    new_upper, new_lower = two_bone_ik(root, upper, lower, THIGH, SHIN, end)
    knee_after, _ = chain(new_upper, new_lower, root)
    assert np.linalg.norm(knee_after - knee_before, axis=1).max() < 1e-4  # 1 micron: acos near straight


def test_a_target_out_of_reach_gets_the_stretched_leg_pointing_at_it(leg):
    upper, lower, root = leg
    far = root + np.array([0.0, -200.0, 30.0])
    new_upper, new_lower = two_bone_ik(root, upper, lower, THIGH, SHIN, far)
    _, end = chain(new_upper, new_lower, root)
    length = 40 + np.linalg.norm(SHIN)
    np.testing.assert_allclose(np.linalg.norm(end - root, axis=1), REACH * length, rtol=1e-9)
    direction = (far - root) / np.linalg.norm(far - root, axis=1, keepdims=True)
    np.testing.assert_allclose((end - root) / np.linalg.norm(end - root, axis=1, keepdims=True), direction, atol=1e-9)


def test_the_kernel_and_its_twin_agree_on_every_kind_of_target(leg):
    import expressive_mocap as em
    from expressive_mocap import reference

    if not em.rust_available():
        pytest.skip("the Rust extension is not built")
    from expressive_mocap import _core

    upper, lower, root = leg
    rng = np.random.default_rng(4)
    F = len(root)
    straight = quat.normalize(np.tile([0.0, 0.0, 0.0, 1.0], (F, 1)))  # a straight knee: no bend plane
    # Targets within reach, beyond it, nearer than the bones' difference, and on the root.
    distance = np.r_[rng.uniform(10, 75, F - 6), 200.0, 200.0, 0.5, 0.5, 0.0, 0.0][:, None]
    direction = rng.normal(size=(F, 3))
    target = root + direction / np.linalg.norm(direction, axis=1, keepdims=True) * distance
    for lows in (lower, straight):
        args = (root, upper, lows, np.tile(THIGH, (F, 1)), np.tile(SHIN, (F, 1)), target)
        for got, want in zip(_core.two_bone_ik(*args), reference.two_bone_ik(*args)):
            np.testing.assert_allclose(got, want, atol=1e-12)
