"""The intensity estimate of the exaggeration on real clips (Bandai-Namco-Research-Motiondataset,
CC BY-NC 4.0): it estimates the intensity of its own training clips and of another session's,
and says when a clip lies outside the trained range."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em


def test_training_walks_are_estimated_near_their_own_intensity(walks_model, walks_people):
    """Each of the 24 training clips, estimated as exaggerate estimates a motion (its cycles'
    coefficients, mean and bootstrap). Measured per level, mean (standard deviation) over the 8
    takes: 1.07 (0.09), 1.86 (0.08), 3.07 (0.10); largest error 0.25; reading the DOFs' means
    too (estimate_offsets=True) 1.06 (0.05), 1.88 (0.09), 3.06 (0.09), largest error 0.24 (take
    5's normal walk, 1.76). Before (unweighted least squares): 1.28 (0.02), 1.43 (0.03), 3.29 (0.05)."""
    from expressive_mocap.exaggeration import exaggerate

    model, people = walks_model, walks_people
    estimates = np.array(
        [[exaggerate(model, clip, 2.0, lock_feet=False)[1].estimate for clip in person] for person in people]
    )
    k = np.vectorize(lambda e: e.k)(estimates)
    for level, column in zip([1, 2, 3], k.T):
        assert abs(column.mean() - level) < 0.15, (level, column)
        assert np.abs(column - level).max() < 0.3, (level, column)
    # The uncertainty is about the size of the errors (measured: RMS of error / uncertainty 0.89;
    # 1.00 leaving each take out of training in turn, reading the means too), and the fit is as
    # good as the training's (residuals 0.67-1.22).
    sigma = np.vectorize(lambda e: e.uncertainty)(estimates)
    z = np.sqrt(np.mean(((k - [1, 2, 3]) / sigma) ** 2))
    assert 0.5 < z < 1.5, z
    residual = np.vectorize(lambda e: e.residual)(estimates)
    assert 0.5 < residual.mean() < 1.5 and not any(e.warning() for e in estimates.ravel())


def test_the_estimate_is_reported_and_warns_outside_the_trained_range(walks_model, bandai2_dir):
    """An active run is not a walk more 'active' than any trained: its estimate lies beyond the
    range (measured 4.27 +- 0.34), the fit residual says it fits badly (4.6; the training walks
    at most 1.22), and both the report and a warning say so. Before: a bare number and no warning."""
    from expressive_mocap.exaggeration import exaggerate

    model = walks_model
    run = em.read_bvh(bandai2_dir / "dataset-2_run_active_001.bvh")
    with pytest.warns(UserWarning, match="outside the trained range 1-3.*fits the model poorly"):
        _, report = exaggerate(model, run, 3.0, lock_feet=False)
    e = report.estimate
    assert e.outside and e.poor_fit, e
    text = report.text()
    assert f"{e.k:.3g} +- {e.uncertainty:.2g} (estimated)" in text and "fit residual" in text and "warning:" in text
    _, given = exaggerate(model, run, 3.0, current=2.0, lock_feet=False)
    assert given.estimate is None and "estimated" not in given.text()


def test_dataset1_walks_are_estimated_near_their_own_intensity(bandai1_dir):
    """dataset-1's walks tired / normal / active = 1 / 2 / 3 (take 1: one person; take 2's normal
    walk is 31 frames, no cycle), each estimated with a model from those three. Measured 0.95,
    2.01, 2.98 (reading the DOFs' means too, 0.97, 2.06, 2.97). Before: 0.66, 2.68, 2.66 (normal
    and active in the wrong order)."""
    from expressive_mocap.exaggeration import exaggerate, train

    clips = [em.read_bvh(bandai1_dir / f"dataset-1_walk_{style}_001.bvh") for style in ("tired", "normal", "active")]
    model = train([clips], [1, 2, 3])
    k = [exaggerate(model, clip, 2.0, lock_feet=False)[1].estimate.k for clip in clips]
    np.testing.assert_allclose(k, [1, 2, 3], atol=0.2)


@pytest.mark.parametrize("degree", [2, 3])
def test_a_curved_mapping_is_inverted_at_its_exact_least_squares_intensity(degree):
    """Mappings of degree 2 or more (continued along their tangents beyond the levels): the
    intensity minimising the weighted error is found exactly, as a grid of 200,001 points over
    the searched range finds it, and coefficients made at an intensity give that intensity back."""
    from expressive_mocap.exaggeration.estimate import weighted_intensity
    from expressive_mocap.exaggeration.fitting import mapped

    rng = np.random.default_rng(degree)
    levels = np.array([1.0, 2.0, 3.0])
    mappings, weights = rng.normal(size=(7, 4, degree + 1)), rng.uniform(0.1, 1.0, size=(7, 4))
    truth = rng.uniform(0.0, 4.0, size=40)
    noisy = mapped(mappings, truth, levels) + 0.3 * rng.normal(size=(40, 7, 4))
    k = weighted_intensity(mappings, weights, noisy, levels)
    grid = np.linspace(-3.0, 7.0, 200_001)  # the trained range widened by twice its span
    errors = np.einsum("nr,bgnr->bg", weights, (mapped(mappings, grid, levels)[None] - noisy[:, None]) ** 2)
    found = np.einsum("nr,bnr->b", weights, (mapped(mappings, k, levels) - noisy) ** 2)
    assert np.all(found <= errors.min(axis=1) + 1e-9)
    clean = mapped(mappings, truth, levels)
    assert np.allclose(weighted_intensity(mappings, weights, clean, levels), truth, atol=1e-6)


def test_a_curved_mapping_goes_on_straight_beyond_the_levels():
    """A parabola through three levels turns back past its vertex; beyond the trained levels the
    mapping follows the tangent at the nearer end instead: continuous there, with the end's slope,
    and straight."""
    from expressive_mocap.exaggeration.fitting import mapped

    levels = np.array([1.0, 2.0, 3.0])
    mappings = np.array([[[1.0, -3.0, 2.0]]])  # (k - 1)(k - 2): its vertex at 1.5, back up below it
    inside = mapped(mappings, levels, levels)[..., 0, 0]
    assert np.allclose(inside, [0.0, 0.0, 2.0])  # the polynomial itself within the levels
    below = mapped(mappings, np.array([0.0, 0.5, 1.0 - 1e-9]), levels)[..., 0, 0]
    assert np.allclose(below, [1.0, 0.5, 0.0], atol=1e-8)  # slope -1 at 1: it goes on rising as k falls
    above = mapped(mappings, np.array([3.0 + 1e-9, 4.0, 5.0]), levels)[..., 0, 0]
    assert np.allclose(above, [2.0, 5.0, 8.0], atol=1e-8)  # slope 3 at 3
    assert np.allclose(mapped(mappings, 0.0)[..., 0, 0], 2.0)  # without the levels: the parabola
