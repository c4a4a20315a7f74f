"""Kernels misused: wrong dtypes, non-contiguous arrays, mismatched shapes, zero frames, one
joint, NaN and infinity. Through the public wrappers (ops.py, both backends) and the Rust
functions called directly: a Python exception naming the argument, or the documented result
(README, "Kernels under misuse"), the same for both backends; never a PanicException."""

import numpy as np
import pytest

import expressive_mocap as em
from conftest import BACKENDS
from expressive_mocap import ops as k
from expressive_mocap import reference
from expressive_mocap.body import contacts as foot_contacts
from kernel_cases import CORE, RNG, contacts_args, features_args, layout, mlp_args, quats

# Each public wrapper: a function of (frames, joints) giving its arguments, and the arrays'
# names in order (what an error must name when that argument is broken).
WRAPPERS = {
    "euler_to_quat": (k.euler_to_quat, lambda f, j: (RNG.uniform(-180, 180, (f, j, 3)), "ZXY"), ["angles"]),
    "quat_to_euler": (k.quat_to_euler, lambda f, j: (quats(f, j), "YXZ"), ["quats"]),
    "forward_kinematics": (
        k.forward_kinematics,
        lambda f, j: (quats(f, j), RNG.normal(size=(f, j, 3)), np.arange(-1, j - 1)),
        ["rotations", "translations", "parents"],
    ),
    "decode_channels": (
        k.decode_channels,
        lambda f, j: (RNG.uniform(-90, 90, (f, 3 + 3 * j)), *layout(j)),
        ["values", "rotation_columns", "orders", "position_columns", "offsets"],
    ),
    "decouple_rotations": (
        k.decouple_rotations,
        lambda f, j: (quats(f, j), quats(j, f).transpose(1, 0, 2), 2.0, 4.0),
        ["original", "body"],
    ),
    "compose_rotations": (
        k.compose_rotations,
        lambda f, j: (quats(f, j), quats(j, f).transpose(1, 0, 2), 1.5),
        ["expressive", "body"],
    ),
    "mlp_forward": (k.mlp_forward, lambda f, j: mlp_args(f), ["x"]),
}


def call(name, args):
    return WRAPPERS[name][0](*args)


def outputs(result):
    return result if isinstance(result, tuple) else (result,)


def both_backends(name, args):
    """The outputs of the wrapper under each available backend."""
    results = []
    for backend in BACKENDS:
        with em.use_backend(backend):
            results.append(outputs(call(name, args)))
    return results


@pytest.mark.parametrize("name", WRAPPERS)
def test_zero_frames_give_empty_outputs_of_the_right_shape(name):
    args = WRAPPERS[name][1](0, 3)
    shapes = {tuple(o.shape) for result in both_backends(name, args) for o in [result[0]]}
    assert len(shapes) == 1 and next(iter(shapes))[0] == 0, shapes


@pytest.mark.parametrize("name", WRAPPERS)
def test_a_single_joint_and_a_single_frame_agree_across_backends(name):
    for frames, joints in [(1, 1), (4, 1), (1, 5)]:
        args = WRAPPERS[name][1](frames, joints)
        first, *others = both_backends(name, args)
        for other in others:
            for a, b in zip(first, other):
                np.testing.assert_allclose(a, b, atol=1e-9)


@pytest.mark.parametrize("name", WRAPPERS)
def test_non_contiguous_inputs_give_the_contiguous_result(name, backend):
    args = WRAPPERS[name][1](6, 3)
    strided = tuple(np.asfortranarray(a) if isinstance(a, np.ndarray) and a.ndim > 1 else a for a in args)
    assert any(isinstance(a, np.ndarray) and not a.flags.c_contiguous for a in strided)
    for a, b in zip(outputs(call(name, args)), outputs(call(name, strided))):
        np.testing.assert_array_equal(a, b)


# Integer quaternions are not unit quaternions: the wrappers that take rotations are left out.
@pytest.mark.parametrize(
    "name",
    [
        n
        for n in WRAPPERS
        if n not in ("quat_to_euler", "decouple_rotations", "compose_rotations", "forward_kinematics")
    ],
)
def test_integer_arrays_are_converted_like_floats(name, backend):
    args = WRAPPERS[name][1](3, 2)
    rounded = tuple(
        np.round(a).astype(np.int32) if isinstance(a, np.ndarray) and a.dtype.kind == "f" else a for a in args
    )
    as_float = tuple(a.astype(np.float64) if isinstance(a, np.ndarray) and a.dtype == np.int32 else a for a in rounded)
    for a, b in zip(outputs(call(name, rounded)), outputs(call(name, as_float))):
        np.testing.assert_array_equal(a, b)


def broken(name, index, how):
    """The wrapper's arguments for 4 frames and 3 joints with array argument ``index`` broken."""
    args = list(WRAPPERS[name][1](4, 3))
    if name == "mlp_forward" and index > 0:
        raise AssertionError
    value = args[index]
    if how == "text":
        args[index] = np.full(value.shape, "x", dtype="<U1")
    elif how == "shape":
        args[index] = value[..., :-1] if value.ndim > 1 else value[:-1]
    elif how == "object":
        args[index] = np.array([None] * len(value), dtype=object)
    return tuple(args)


CASES = [(name, i, arg) for name, (_, _, names) in WRAPPERS.items() for i, arg in enumerate(names)]


@pytest.mark.parametrize("how", ["text", "shape", "object"])
@pytest.mark.parametrize("name, index, argument", CASES)
def test_a_broken_argument_is_an_error_naming_it(name, index, argument, how, backend):
    args = broken(name, index, how)
    with pytest.raises((em.errors.ArgumentError, TypeError)) as caught:
        call(name, args)
    # A wrong dtype names the argument; a wrong shape names it or one it disagrees with.
    names = [argument] if how != "shape" else WRAPPERS[name][2]
    assert any(f"`{n}`" in str(caught.value) for n in names), str(caught.value)
    assert type(caught.value).__name__ != "PanicException"


# ----------------------------------------------------------------------- NaN and infinity


@pytest.mark.parametrize("bad", [np.nan, np.inf])
@pytest.mark.parametrize("name", WRAPPERS)
def test_nan_and_infinity_propagate_the_same_way_in_both_backends(name, bad):
    # Documented (README, "Kernels under misuse"): NaN in gives NaN in the outputs it feeds;
    # infinity gives what the arithmetic gives (tanh(inf) = 1, a quaternion with an infinite
    # w turns by 0 degrees); both backends alike.
    args = list(WRAPPERS[name][1](5, 4))
    poisoned = args[0].copy()
    poisoned.reshape(-1)[7] = bad
    args[0] = poisoned
    results = both_backends(name, tuple(args))
    for result in results:
        assert np.isnan(bad) <= any(np.isnan(o).any() for o in result), "the NaN vanished"
    first, *others = results
    for other in others:
        for a, b in zip(first, other):
            np.testing.assert_array_equal(np.isfinite(a), np.isfinite(b))
            np.testing.assert_allclose(np.where(np.isfinite(a), a, 0), np.where(np.isfinite(b), b, 0), atol=1e-9)


# ----------------------------------------------------------------------- the Rust functions directly

core = pytest.importorskip("expressive_mocap._core") if em.rust_available() else None
rust_only = pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")


def test_every_rust_function_is_covered():
    assert set(CORE) == set(reference.__all__) - {"num_threads"}


@rust_only
@pytest.mark.parametrize(
    "name, index, argument", [(n, i, a) for n, (_, names) in CORE.items() for i, a in enumerate(names) if a]
)
@pytest.mark.parametrize("how", ["dtype", "strided", "ndim"])
def test_rust_functions_name_a_broken_array_argument(name, index, argument, how):
    args = list(CORE[name][0](6))
    value = args[index]
    if how == "dtype":
        args[index] = value.astype(np.complex128)
    elif how == "strided":
        args[index] = np.repeat(value, 2, axis=-1)[..., ::2]
        assert not args[index].flags.c_contiguous
    else:
        args[index] = value[None]
    with pytest.raises((TypeError, em.errors.ArgumentError)) as caught:
        getattr(core, name)(*args)
    assert argument in str(caught.value), str(caught.value)


@rust_only
@pytest.mark.parametrize(
    "name, index, argument",
    [(n, i, a) for n, (make, names) in CORE.items() for i, a in enumerate(names) if a and np.ndim(make(6)[i]) >= 2],
)
def test_rust_functions_refuse_fortran_ordered_arrays(name, index, argument):
    # Contiguous, but in the other order: read as C order its numbers would come transposed.
    args = list(CORE[name][0](6))
    args[index] = np.asfortranarray(args[index])
    assert not args[index].flags.c_contiguous
    with pytest.raises(em.errors.ArgumentTypeError, match=f"`{argument}`") as caught:
        getattr(core, name)(*args)
    assert isinstance(caught.value, em.MocapError) and isinstance(caught.value, TypeError)  # both


def flatten(result):
    if isinstance(result, (tuple, list)):
        return [leaf for item in result for leaf in flatten(item)]
    return [result]


@rust_only
@pytest.mark.parametrize("name", CORE)
def test_rust_functions_take_zero_frames_like_their_twins(name):
    rust, twin = (flatten(getattr(module, name)(*CORE[name][0](0))) for module in (core, reference))
    assert [np.shape(r) for r in rust] == [np.shape(t) for t in twin]


@rust_only
@pytest.mark.parametrize(
    "name, args, argument",
    [
        ("foot_contacts", lambda: contacts_args(5)[:1] + (np.nan,) + contacts_args(5)[2:], "frame_time"),
        ("foot_contacts", lambda: contacts_args(5)[:5] + (0,) + contacts_args(5)[6:], "min_frames"),
        ("air_time", lambda: (np.zeros((3, 2), bool), -1.0), "frame_time"),
        ("dynamic_features", lambda: features_args(4)[:4] + (np.inf,) + features_args(4)[5:], "frame_time"),
        ("dynamic_features", lambda: features_args(4)[:5] + (0.0,) + features_args(4)[6:], "height"),
        ("dynamic_features", lambda: features_args(4)[:8] + (0,), "window"),
        ("decouple_rotations", lambda: CORE["decouple_rotations"][0](3)[:2] + (np.nan, 4.0), "gain"),
        ("compose_rotations", lambda: CORE["compose_rotations"][0](3)[:2] + (np.inf,), "scale"),
        ("parse_motion_block", lambda: (b"1 2 3\n", 10, 1, 3), "start"),
        ("parse_motion_block", lambda: (b"1 2 3\n", 0, 1, 2**62), "frames"),
        (
            "decode_channels",
            lambda: (np.zeros((2**40, 0)), np.full((1, 3), -1), layout(1)[1], np.full((1, 3), -1), np.zeros((1, 3))),
            "values",
        ),
        ("air_time", lambda: (np.zeros((0, 2**40), bool), 0.1), None),
        ("foot_contacts", lambda: (np.zeros((0, 2**20, 2**20, 3)), 0.1, 0.0, 1.0, 1.0, 3, False), None),
        (
            "mlp_forward",
            lambda: (np.zeros((2**21, 1)), [np.zeros((1, 2**21))], [np.zeros(2**21)], ["linear"]),
            "weights",
        ),
    ],
)
def test_rust_functions_refuse_bad_scalars_and_absurd_shapes(name, args, argument):
    # Absurd shapes (zero-size arrays claiming 10^12 frames, outputs of terabytes) are errors,
    # not aborts; a huge foot count with no frames is an empty answer, not a hang.
    if argument is None:
        result = getattr(core, name)(*args())
        assert result.size == 0
        return
    with pytest.raises(em.errors.ArgumentError) as caught:
        getattr(core, name)(*args())
    assert f"`{argument}`" in str(caught.value), str(caught.value)


@pytest.mark.parametrize("contacts", [np.array([["x", ""]]), np.array([[None, 1]], dtype=object), np.zeros(3, bool)])
def test_air_time_refuses_what_is_not_flags(contacts, backend):
    # Text would have been cast to bool: "x" and "" silently True and False.
    with pytest.raises(em.MocapError, match="`contacts`"):
        foot_contacts.air_time(contacts, 0.1)
