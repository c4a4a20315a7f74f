"""Training: the backward pass against finite differences, the split by group, and on synthetic
data whose poses are a smooth known function of the features, every stage beating the mean pose."""

import numpy as np
import pytest

from expressive_mocap.decoupling import lbfgs
from expressive_mocap.decoupling import training as train
from expressive_mocap.decoupling.network import Mlp
from expressive_mocap.errors import ArgumentError

pytest.importorskip("scipy")


def synthetic(n_groups=30, frames=50, d=24, seed=0):
    """A small known problem (see :func:`train.synthetic_data`)."""
    return train.synthetic_data(n_groups, frames, d=d, seed=seed)


@pytest.fixture(scope="module")
def trained():
    X, P, groups = synthetic()
    net, report = train.train_stacked_network(X, P, groups, hidden=20, regression_hidden=20, max_iter=100, log=None)
    return X, P, groups, net, report


def test_gradient_matches_finite_differences():
    rng = np.random.default_rng(0)
    params = lbfgs.init_params(rng, (3, 5, 4, 2))
    params = [(w, rng.normal(scale=0.3, size=b.shape)) for w, b in params]
    acts = ("tanh", "tanh", "linear")
    x, y = rng.normal(size=(7, 3)), rng.normal(size=(7, 2))
    loss, grads = lbfgs.loss_and_grad(params, acts, x, y, weight_decay=0.01)
    flat, analytic = lbfgs._pack(params), lbfgs._pack(grads)
    numeric = np.empty_like(flat)
    h = 1e-6
    for i in range(len(flat)):
        up, down = flat.copy(), flat.copy()
        up[i] += h
        down[i] -= h
        numeric[i] = (
            lbfgs.loss_and_grad(lbfgs._unpack(up, params), acts, x, y, 0.01)[0]
            - lbfgs.loss_and_grad(lbfgs._unpack(down, params), acts, x, y, 0.01)[0]
        ) / (2 * h)
    np.testing.assert_allclose(analytic, numeric, rtol=1e-6, atol=1e-9)
    assert loss == pytest.approx(
        np.mean((Mlp(zip(*zip(*params), acts))(x) - y) ** 2) + 0.01 * sum(np.sum(w**2) for w, _ in params)
    )


def test_split_by_group_keeps_groups_whole():
    groups = np.repeat(np.array(["c0", "c1", "c2", "c3", "c4", "c5", "c6", "c7", "c8", "c9"]), np.arange(10, 110, 10))
    train_rows, test_rows = train.split_by_group(groups, 0.3, seed=3)
    assert not set(groups[train_rows]) & set(groups[test_rows])
    assert np.array_equal(np.sort(np.concatenate([train_rows, test_rows])), np.arange(len(groups)))
    assert 0.3 <= len(test_rows) / len(groups) < 0.3 + 100 / len(groups)  # stops at the first group past 30%
    again = train.split_by_group(groups, 0.3, seed=3)
    assert np.array_equal(again[0], train_rows) and np.array_equal(again[1], test_rows)
    with pytest.raises(ArgumentError, match="at least 2 groups"):
        train.split_by_group(np.zeros(5), 0.3)


def test_corruption_masks_ten_to_thirty_percent():
    z = np.ones((2000, 50))
    corrupted = train.corrupt(np.random.default_rng(0), z, mask=(0.1, 0.3), noise=0.0)
    masked = np.mean(corrupted == 0, axis=1)
    assert 0.18 < masked.mean() < 0.22 and masked.min() > 0.0 and masked.max() < 0.45


def test_stack_beats_the_mean_pose_on_held_out_clips(trained):
    X, P, groups, net, report = trained
    assert isinstance(net, Mlp) and net.shape == (19, 20, 20, 24)
    assert [layer.activation for layer in net.layers] == ["tanh", "tanh", "linear"]
    train_rows, test_rows = train.split_by_group(groups, 0.3, seed=0)
    assert report.split.test_rows == len(test_rows)
    mean_pose = report.mean_pose.test_mse
    assert report.fine_tuned.test_mse < 0.02 * mean_pose
    assert report.fine_tuned.test_variance_explained > 0.97
    assert report.autoencoder.test_variance_explained > 0.9
    assert report.fine_tuned.test_mse <= report.stack.test_mse
    assert report.plain.test_mse < 0.02 * mean_pose
    # The network takes raw features (normalisation folded in) and scores what the report says.
    assert np.mean((net(X[test_rows]) - P[test_rows]) ** 2) == pytest.approx(report.fine_tuned.test_mse, rel=1e-9)
    assert net(X[test_rows].astype(np.float32)).dtype == np.float32


def test_training_is_deterministic_under_a_seed():
    X, P, groups = synthetic(n_groups=8, frames=20, d=6)
    kwargs = {"hidden": 6, "regression_hidden": 5, "max_iter": 15, "compare_plain": False, "log": None}
    net_a, report_a = train.train_stacked_network(X, P, groups, seed=4, **kwargs)
    net_b, report_b = train.train_stacked_network(X, P, groups, seed=4, **kwargs)
    for la, lb in zip(net_a.layers, net_b.layers):
        np.testing.assert_array_equal(la.weights, lb.weights)
    assert report_a.fine_tuned.test_mse == report_b.fine_tuned.test_mse
    _, report_c = train.train_stacked_network(X, P, groups, seed=5, **kwargs)
    assert report_c.fine_tuned.test_mse != report_a.fine_tuned.test_mse


def test_sweep_and_progress_lines():
    X, P, groups = synthetic(n_groups=10, frames=30, d=12)
    lines = []
    results = train.sweep_autoencoder(P, groups, hiddens=(12, 2), max_iter=60, rounds=1, log=lines.append)
    assert set(results) == {12, 2}
    assert results[12].test_mse < results[2].test_mse  # a 2-unit code cannot hold a 6-D manifold
    assert any("iteration 50/" in line for line in lines) and any("H=2: train MSE" in line for line in lines)


def test_bad_shapes_name_the_argument():
    with pytest.raises(ArgumentError, match="`groups`"):
        train.train_stacked_network(np.zeros((10, 3)), np.zeros((10, 2)), np.zeros(9), log=None)
    with pytest.raises(ArgumentError, match="`X`, `P`"):
        train.train_stacked_network(np.zeros((10, 3)), np.zeros((11, 2)), np.zeros(10), log=None)
