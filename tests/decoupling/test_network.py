"""MLP inference: a layer by hand, Rust/NumPy parity in float32 and float64, odd sizes,
non-contiguous inputs, errors that name the argument, and saving without pickle."""

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap import reference
from expressive_mocap.decoupling.network import Layer, Mlp
from expressive_mocap.errors import ArgumentError, ModelError

RTOL = {np.float32: 1e-5, np.float64: 1e-12}  # relative to the largest output


def random_net(rng, widths, last="linear"):
    layers = []
    for i, (a, b) in enumerate(zip(widths[:-1], widths[1:])):
        act = last if i == len(widths) - 2 else "tanh"
        layers.append(Layer(rng.normal(size=(a, b)) / np.sqrt(a), rng.normal(scale=0.5, size=b), act))
    return Mlp(layers)


def test_one_layer_by_hand(backend):
    net = Mlp([([[1.0, -1.0], [0.5, 2.0]], [0.0, 1.0], "tanh"), ([[2.0], [3.0]], [0.5], "linear")])
    x = np.array([[1.0, 2.0]])
    h = np.tanh([1.0 * 1 + 2 * 0.5, -1.0 + 2 * 2 + 1])
    np.testing.assert_allclose(net(x), [[2 * h[0] + 3 * h[1] + 0.5]], rtol=1e-14)
    assert net(np.array([1.0, 2.0])).shape == (1,)  # one row without a batch dimension


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
@pytest.mark.parametrize(
    ("rows", "widths"),
    [(0, (19, 30, 8)), (1, (19, 30, 8)), (5, (1, 1, 1)), (7, (3, 1, 4)), (1000, (19, 300, 300, 80)), (129, (5, 17, 2))],
)
def test_rust_matches_numpy_twin(dtype, rows, widths):
    from expressive_mocap import _core

    rng = np.random.default_rng(rows + len(widths))
    net = random_net(rng, widths)
    x = rng.normal(size=(rows, widths[0])).astype(dtype)
    weights, biases = net._arrays(dtype)
    acts = [layer.activation for layer in net.layers]
    ours = _core.mlp_forward(x, weights, biases, acts)
    twin = reference.mlp_forward(x, weights, biases, acts)
    assert ours.dtype == twin.dtype == dtype and ours.shape == (rows, widths[-1])
    scale = max(np.abs(twin).max(initial=0.0), 1.0)
    np.testing.assert_allclose(ours, twin, rtol=0, atol=RTOL[dtype] * scale)


def test_dtype_is_kept_and_other_dtypes_run_in_float64(backend):
    net = random_net(np.random.default_rng(1), (4, 6, 3))
    x = np.random.default_rng(2).normal(size=(10, 4))
    assert net(x.astype(np.float32)).dtype == np.float32
    assert net(x).dtype == np.float64
    assert net(np.ones((2, 4), dtype=np.int64)).dtype == np.float64
    np.testing.assert_allclose(net(x.astype(np.float32)), net(x), rtol=0, atol=1e-5)


def test_non_contiguous_and_batched_inputs(backend):
    rng = np.random.default_rng(3)
    net = random_net(rng, (5, 9, 2))
    big = rng.normal(size=(40, 12))
    x = big[::3, 2:12:2]  # strided rows and columns
    assert not x.flags.c_contiguous
    np.testing.assert_allclose(net(x), net(np.ascontiguousarray(x)), rtol=0, atol=1e-15)
    fortran = np.asfortranarray(rng.normal(size=(8, 5)))
    np.testing.assert_allclose(net(fortran), net(np.ascontiguousarray(fortran)), rtol=0, atol=1e-15)
    batched = rng.normal(size=(3, 4, 5))
    np.testing.assert_allclose(net(batched), net(batched.reshape(12, 5)).reshape(3, 4, 2), rtol=0, atol=1e-15)


def test_errors_name_the_argument(backend):
    rng = np.random.default_rng(4)
    w1, b1 = rng.normal(size=(4, 6)), np.zeros(6)
    w2, b2 = rng.normal(size=(5, 2)), np.zeros(2)
    x = np.zeros((3, 4))
    with pytest.raises(em.errors.ArgumentError, match=r"`x`.*\[N, 4\]"):
        em.mlp_forward(np.zeros((3, 7)), [w1], [b1], ["tanh"])
    with pytest.raises(em.errors.ArgumentError, match="`weights`: layer 1 takes 5 inputs but layer 0 has 6 outputs"):
        em.mlp_forward(x, [w1, w2], [b1, b2], ["tanh", "linear"])
    with pytest.raises(em.errors.ArgumentError, match="`biases`: layer 0"):
        em.mlp_forward(x, [w1], [np.zeros(5)], ["tanh"])
    with pytest.raises(
        em.errors.ArgumentError, match="`activations`: layer 0.*'relu'|`activations`: layer 0.*\"relu\""
    ):
        em.mlp_forward(x, [w1], [b1], ["relu"])
    with pytest.raises(em.errors.ArgumentError, match="`biases`: expected one for each"):
        em.mlp_forward(x, [w1], [], ["tanh"])
    with pytest.raises(em.errors.ArgumentError, match="`weights`: layer 0 must be 2-D"):
        em.mlp_forward(x, [np.zeros(4)], [b1], ["tanh"])
    with pytest.raises(em.errors.ArgumentError, match="`weights`.*at least one layer"):
        em.mlp_forward(x, [], [], [])
    with pytest.raises(ArgumentError, match="layer 1 takes 5 inputs but layer 0 has 6 outputs"):
        Mlp([(w1, b1, "tanh"), (w2, b2, "linear")])


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
def test_rust_binding_refuses_mixed_dtypes_and_non_contiguous_arrays():
    from expressive_mocap import _core

    w, b = np.zeros((4, 2)), np.zeros(2)
    with pytest.raises(TypeError, match="`weights`: layer 0 must be a 2-D float32"):
        _core.mlp_forward(np.zeros((3, 4), np.float32), [w], [b], ["tanh"])
    with pytest.raises(TypeError, match="`x`: expected a 2-D float32 or float64"):
        _core.mlp_forward(np.zeros((3, 4), np.int32), [w], [b], ["tanh"])
    with pytest.raises(TypeError, match="`x`: expected a C-contiguous array"):
        _core.mlp_forward(np.zeros((6, 4))[::2], [w], [b], ["tanh"])


def test_save_and_load_without_pickle(tmp_path, backend):
    net = random_net(np.random.default_rng(5), (19, 30, 12, 8))
    path = tmp_path / "net.npz"
    np.savez(path, **net.to_arrays("body"), other=np.arange(3))
    with np.load(path, allow_pickle=False) as arrays:
        loaded = Mlp.from_arrays(arrays, "body")
    assert loaded.shape == net.shape == (19, 30, 12, 8)
    assert [layer.activation for layer in loaded.layers] == ["tanh", "tanh", "linear"]
    x = np.random.default_rng(6).normal(size=(4, 19))
    np.testing.assert_array_equal(loaded(x), net(x))
    with pytest.raises(ModelError, match="prefix 'nope'"):
        Mlp.from_arrays(np.load(path), "nope")


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
def test_concurrent_calls_match_serial_calls():
    from concurrent.futures import ThreadPoolExecutor

    net = random_net(np.random.default_rng(7), (19, 64, 64, 80))
    batches = [
        np.random.default_rng(s).normal(size=(3000, 19)).astype(dt) for s in range(4) for dt in (np.float32, np.float64)
    ]
    serial = [net(x) for x in batches]
    with ThreadPoolExecutor(4) as pool:
        concurrent = list(pool.map(net, batches))
    for a, b in zip(serial, concurrent):
        np.testing.assert_array_equal(a, b)
