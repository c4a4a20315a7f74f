"""The feet's smoothing for noisy positions (:func:`~expressive_mocap.skeletons.denoise.steady_feet`),
on made-up tracks (no data needed): a steady velocity passes unchanged, a contact is held still,
and the banded system is the penalised least-squares problem it stands for."""

from __future__ import annotations

import numpy as np

from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.skeletons.denoise import _penalised, steady_feet


def feet_of_walk():
    walk, _ = walk_and_wave()
    jmap = find_joint_map(walk.skeleton)
    return walk.positions(), jmap, [jmap[f"{s}_{p}"] for s in ("left", "right") for p in ("foot", "toes")]


def test_the_banded_system_is_the_penalised_problem():
    rng = np.random.default_rng(0)
    frames = 12
    velocity, acceleration = rng.random(frames - 1), rng.random(frames - 2)
    d1, d2 = np.diff(np.eye(frames), axis=0), np.diff(np.eye(frames), n=2, axis=0)
    dense = np.eye(frames) + d1.T @ np.diag(velocity) @ d1 + d2.T @ np.diag(acceleration) @ d2
    banded = _penalised(frames, velocity, acceleration)
    for i in range(frames):
        for j in range(max(0, i - 2), min(frames, i + 3)):
            assert np.isclose(banded[2 + i - j, j], dense[i, j]), (i, j)


def test_a_steady_velocity_passes_and_a_contact_is_held():
    points, jmap, feet = feet_of_walk()
    frames = len(points)
    line = np.linspace(0.0, 50.0, frames)[:, None, None] * np.array([0.3, 0.1, 1.0]) + points[:1]
    none = np.zeros((frames, 2), bool)
    moved = steady_feet(points, line, none, jmap, 30.0)
    # no contact: a foot moving at one speed keeps it, to its ends (a Gaussian bends them)
    assert np.allclose(moved[:, feet], line[:, feet], atol=1e-9)
    rng = np.random.default_rng(1)
    still = np.repeat(points[:1], frames, axis=0)
    noisy = still + rng.normal(0.0, 1.0, still.shape)
    held = steady_feet(still, noisy, np.ones((frames, 2), bool), jmap, 30.0)
    loose = steady_feet(still, noisy, none, jmap, 30.0)
    speed = lambda p: np.linalg.norm(np.diff(p[:, feet], axis=0), axis=-1).mean()  # noqa: E731
    assert speed(loose) < 0.2 * speed(noisy)  # measured: 0.12 against 1.6
    assert speed(held) < 0.5 * speed(loose)  # a contact holds the foot still: measured 0.044
    others = [j for j in range(points.shape[1]) if j not in feet]
    assert np.array_equal(held[:, others], still[:, others])  # only the feet are touched
