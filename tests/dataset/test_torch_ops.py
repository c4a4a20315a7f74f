"""expressive_mocap.dataset.torch_ops against the package's NumPy conventions and kernels: rotation
conversions (random rotations, rotations near the identity and near a half turn, and the real
rotations of dataset-2 clips), forward kinematics against the Rust kernel and its NumPy twin, the
skeleton graph of a preprocessed dataset, the loss terms against the stored velocities and
contacts, gradients by ``torch.autograd.gradcheck`` in float64, and the examples of docs/torch.md.
Real clips: Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0. Skipped without torch."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap import ops
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.dataset.representations import decode, encode
from expressive_mocap.rotations import quat

torch = pytest.importorskip("torch")
pytestmark = pytest.mark.torch

from expressive_mocap.dataset import torch_ops as T  # noqa: E402  (after the skip)

REPO = Path(__file__).resolve().parents[2]
CLIPS = ["dataset-2_walk_normal_001", "dataset-2_run_elderly_002", "dataset-2_walk-turn-left_active_002"]
BANDAI_PARENTS = [-1, 0, 1, 2, 3, 4, 3, 6, 7, 8, 3, 10, 11, 12, 1, 14, 15, 16, 1, 18, 19, 20]
FLOAT32 = 1e-5  # parity in float32


def random_quats(n: int, seed: int = 0) -> np.ndarray:
    """Unit quaternions: uniform ones, then some within 1e-4 rad of the identity and of half turns."""
    rng = np.random.default_rng(seed)
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    axes = rng.normal(size=(n // 4, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    small = rng.uniform(1e-7, 1e-4, size=(n // 4, 1))
    near_identity = np.concatenate([axes * np.sin(small / 2), np.cos(small / 2)], axis=-1)
    angle = np.pi - small  # within 1e-4 of a half turn, w > 0
    near_pi = np.concatenate([axes * np.sin(angle / 2), np.cos(angle / 2)], axis=-1)
    return np.concatenate([q, near_identity, near_pi, [[0.0, 0.0, 0.0, 1.0]]])


def same_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``b`` on ``a``'s hemisphere (quaternions q and -q are one rotation)."""
    return np.where(np.sum(a * b, axis=-1, keepdims=True) < 0, -b, b)


def t32(x) -> torch.Tensor:
    return torch.tensor(np.asarray(x), dtype=torch.float32)


def t64(x, grad: bool = False) -> torch.Tensor:
    return torch.tensor(np.asarray(x), dtype=torch.float64, requires_grad=grad)


@pytest.fixture(scope="module")
def real_quats(bandai2_dir) -> np.ndarray:
    """The local rotations of three dataset-2 clips ``[N, 4]``."""
    return np.concatenate([em.read_bvh(bandai2_dir / f"{n}.bvh").rotations.reshape(-1, 4) for n in CLIPS])


@pytest.fixture(scope="module")
def motions(bandai2_dir) -> list:
    return [em.read_bvh(bandai2_dir / f"{n}.bvh") for n in CLIPS]


@pytest.fixture(scope="module")
def folder(bandai2_dir, tmp_path_factory) -> Path:
    """The three clips preprocessed as a model would train on them: 6D rotations, world positions,
    their velocities and the contacts, in a folder named as docs/torch.md names it."""
    root = tmp_path_factory.mktemp("torch_ops")
    (root / "src").mkdir()
    for name in CLIPS:
        os.symlink(bandai2_dir / f"{name}.bvh", root / "src" / f"{name}.bvh")
    summary = preprocess(
        root / "src",
        root / "bandai2",
        keep="positions,rotations,velocities,contacts",
        rotations="6d",
        progress=False,
    )
    assert summary.clips_ok == len(CLIPS)
    return root / "bandai2"


# --------------------------------------------------------------------------- conversions: parity


@pytest.mark.parametrize("form", ["quaternion", "6d", "matrix", "axis-angle"])
def test_encoding_matches_the_numpy_forms_on_random_rotations(form):
    q = random_quats(4000)
    expected = encode(q, form)  # float64
    got = T.from_quat(t32(q), form).numpy()
    np.testing.assert_allclose(got, expected, atol=FLOAT32, rtol=0)


@pytest.mark.parametrize("form", ["quaternion", "6d", "matrix", "axis-angle"])
def test_decoding_matches_the_numpy_forms_on_random_rotations(form):
    q = random_quats(4000, seed=1)
    values = encode(q, form)
    if form in ("quaternion", "6d"):  # a network's output is off its manifold: scale and skew it
        values = values * np.random.default_rng(2).uniform(0.5, 2.0, size=values.shape[:-1] + (1,))
    expected = decode(values, form)
    got = T.to_quat(t32(values), form).numpy()
    assert (got[:, 3] >= 0).all()
    np.testing.assert_allclose(same_rotation(expected, got), expected, atol=FLOAT32, rtol=0)
    # away from the half turn (w = 0, where q and -q swap) the sign is the package's too
    clear = expected[:, 3] > 1e-3
    np.testing.assert_allclose(got[clear], expected[clear], atol=FLOAT32, rtol=0)


def test_the_conversions_match_the_numpy_ones_on_real_rotations(real_quats):
    q = real_quats
    for form in ("6d", "matrix", "axis-angle"):
        np.testing.assert_allclose(T.from_quat(t32(q), form).numpy(), encode(q, form), atol=FLOAT32, rtol=0)
        back = T.to_quat(t32(encode(q, form)), form).numpy()
        np.testing.assert_allclose(same_rotation(q, back), q, atol=FLOAT32, rtol=0)
    np.testing.assert_allclose(T.quat_to_matrix(t32(q)).numpy(), quat.to_matrix(q), atol=FLOAT32, rtol=0)
    m = quat.to_matrix(q)
    np.testing.assert_allclose(
        T.matrix_to_quat(t32(m)).numpy(), decode(m.reshape(-1, 9), "matrix"), atol=FLOAT32, rtol=0
    )


ORDERS = ["ZXY", "XYZ", "YZX", "ZYX", "XZY", "YXZ"]


@pytest.mark.parametrize("order", ORDERS)
def test_euler_angles_match_the_numpy_forms(order):
    """Both ways against representations.encode/decode (the package's Euler kernel) in every
    order: angles where the middle one is clear of the gimbal lock (float32 degrees: 2e-3), and
    everywhere the rotation the angles give."""
    q = random_quats(4000, seed=11)
    form = f"euler:{order}"
    expected = encode(q, "euler", order)
    got = T.from_quat(t32(q), form).numpy().astype(np.float64)
    clear = np.abs(expected[:, 1]) < 85.0
    assert clear.mean() > 0.9
    np.testing.assert_allclose(got[clear], expected[clear], atol=2e-3, rtol=0)
    again = decode(got, "euler", order)
    np.testing.assert_allclose(same_rotation(q, again), q, atol=1e-4, rtol=0)  # the lock's rows too
    back = T.to_quat(t32(expected), form).numpy()
    assert (back[:, 3] >= 0).all()
    np.testing.assert_allclose(same_rotation(q, back), same_rotation(q, decode(expected, "euler", order)), atol=FLOAT32)
    m = T.to_matrix(t32(expected), form).numpy()
    np.testing.assert_allclose(m, quat.to_matrix(decode(expected, "euler", order)), atol=FLOAT32, rtol=0)


def test_euler_angles_of_real_rotations(real_quats):
    q = real_quats
    np.testing.assert_allclose(T.from_quat(t64(q), "euler:ZXY").numpy(), encode(q, "euler", "ZXY"), atol=1e-8, rtol=0)
    values = encode(q, "euler", "ZXY")
    np.testing.assert_allclose(T.to_quat(t32(values), "euler").numpy(), decode(values, "euler"), atol=FLOAT32, rtol=0)


def test_euler_gradients_and_bad_orders():
    rng = np.random.default_rng(12)
    angles = t64(rng.uniform(-170.0, 170.0, size=(20, 3)) * np.array([1.0, 0.45, 1.0]), grad=True)  # middle within 77
    for order in ("ZXY", "XZY"):
        _gradcheck(lambda a, o=order: T.euler_to_quat(a, o), angles)
        q = t64(T.euler_to_quat(angles, order).detach().numpy(), grad=True)
        _gradcheck(lambda x, o=order: T.quat_to_euler(x, o), q)
    with pytest.raises(em.errors.ArgumentError, match=r"euler:XXY"):
        T.to_quat(t32(np.zeros((2, 3))), "euler:XXY")


def test_the_layouts_are_the_packages():
    """A quarter turn about z: x goes to y. The 6D form is column 0 then column 1; the matrix form
    is row after row; the quaternion is x, y, z, w."""
    q = torch.tensor([0.0, 0.0, np.sin(np.pi / 4), np.cos(np.pi / 4)], dtype=torch.float64)
    m = T.quat_to_matrix(q)
    np.testing.assert_allclose(m.numpy() @ [1, 0, 0], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(T.quat_to_sixd(q).numpy(), [0, 1, 0, -1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(T.from_quat(q, "matrix").numpy(), [0, -1, 0, 1, 0, 0, 0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(T.quat_to_axis_angle(q).numpy(), [0, 0, np.pi / 2], atol=1e-12)
    np.testing.assert_allclose(T.quat_rotate(q, torch.tensor([1.0, 0, 0], dtype=torch.float64)), [0, 1, 0], atol=1e-12)


def test_round_trips_and_the_algebra():
    q = torch.tensor(random_quats(2000, seed=3))
    for there, back in (
        (T.quat_to_matrix, T.matrix_to_quat),
        (T.quat_to_sixd, T.sixd_to_quat),
        (T.quat_to_axis_angle, T.axis_angle_to_quat),
    ):
        again = back(there(q)).numpy()
        np.testing.assert_allclose(same_rotation(q.numpy(), again), q.numpy(), atol=1e-12)
    v = T.quat_to_axis_angle(q)
    assert float(v.norm(dim=-1).max()) <= np.pi + 1e-12
    np.testing.assert_allclose(T.matrix_to_axis_angle(T.axis_angle_to_matrix(v)).numpy(), v.numpy(), atol=1e-9)
    np.testing.assert_allclose(T.sixd_to_matrix(T.matrix_to_sixd(T.quat_to_matrix(q))), T.quat_to_matrix(q), atol=1e-12)
    # products: the Hamilton product is the matrices' product; conjugate is the inverse
    a, b = q[:1000], q[1000:2000]
    np.testing.assert_allclose(
        T.quat_to_matrix(T.quat_mul(a, b)), T.quat_to_matrix(a) @ T.quat_to_matrix(b), atol=1e-12
    )
    np.testing.assert_allclose(
        T.quat_mul(a, T.quat_conjugate(a)).numpy(), np.tile([0, 0, 0, 1.0], (1000, 1)), atol=1e-12
    )
    np.testing.assert_allclose(T.quat_mul(a, b).numpy(), quat.mul(a.numpy(), b.numpy()), atol=1e-12)


def test_unnormalised_inputs_give_the_rotation_of_their_unit_one():
    q = torch.tensor(random_quats(200, seed=4))
    scaled = q * torch.linspace(0.2, 5.0, len(q))[:, None].double()
    np.testing.assert_allclose(T.quat_to_matrix(scaled), T.quat_to_matrix(q), atol=1e-12)
    # any two independent vectors make a rotation: orthonormal, determinant 1
    m = T.sixd_to_matrix(torch.randn(500, 6, dtype=torch.float64))
    np.testing.assert_allclose(m.transpose(-1, -2) @ m, torch.eye(3).expand(500, 3, 3).double(), atol=1e-12)
    np.testing.assert_allclose(torch.linalg.det(m), np.ones(500), atol=1e-12)


def test_leading_axes_of_any_number():
    q = torch.tensor(random_quats(120, seed=5)[:120]).reshape(2, 3, 4, 5, 4)
    flat = T.quat_to_sixd(q.reshape(-1, 4))
    assert T.quat_to_sixd(q).shape == (2, 3, 4, 5, 6)
    np.testing.assert_array_equal(T.quat_to_sixd(q).reshape(-1, 6), flat)
    assert T.quat_to_matrix(q).shape == (2, 3, 4, 5, 3, 3)
    assert T.to_quat(T.from_quat(q, "axis-angle"), "axis-angle").shape == q.shape


def test_bad_inputs_are_value_errors_naming_the_argument():
    with pytest.raises(ValueError, match="argument `q`.*\\[\\.\\.\\., 4\\]"):
        T.quat_to_matrix(torch.zeros(3, 3))
    with pytest.raises(ValueError, match="argument `form`.*quaternion, 6d.*euler:ORDER"):
        T.to_quat(torch.zeros(3), "eulers")
    with pytest.raises(ValueError, match="argument `values`"):
        T.to_quat(torch.zeros(5, 4), "6d")
    with pytest.raises(ValueError, match="argument `d`: expected a torch.Tensor"):
        T.sixd_to_matrix(np.zeros(6))


# --------------------------------------------------------------------------- conversions: gradients


def _gradcheck(f, *inputs) -> None:
    assert torch.autograd.gradcheck(f, inputs, eps=1e-6, atol=1e-6, rtol=1e-5)


def test_every_conversion_has_the_gradients_of_its_values():
    q = t64(random_quats(40, seed=6)[np.r_[0:10, 10:20, 20:30]], grad=True)  # plain, near identity, near pi
    _gradcheck(T.quat_to_matrix, q)
    _gradcheck(T.quat_to_sixd, q)
    _gradcheck(T.quat_to_axis_angle, q)
    _gradcheck(lambda x: T.to_quat(x, "quaternion"), q)
    m = t64(quat.to_matrix(q.detach().numpy()), grad=True)
    _gradcheck(T.matrix_to_quat, m)
    _gradcheck(T.matrix_to_sixd, m)
    _gradcheck(T.matrix_to_axis_angle, m)
    d = t64(np.random.default_rng(7).normal(size=(20, 6)), grad=True)
    _gradcheck(T.sixd_to_matrix, d)
    _gradcheck(T.sixd_to_quat, d)
    _gradcheck(T.quat_mul, q[:10], q[10:20])
    _gradcheck(T.quat_rotate, q[:10], t64(np.random.default_rng(8).normal(size=(10, 3)), grad=True))


def test_axis_angle_gradients_near_the_identity_and_near_a_half_turn():
    rng = np.random.default_rng(9)
    axes = rng.normal(size=(12, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    angles = np.array([0.0, 1e-9, 1e-7, 1e-5, 1e-3, 0.5, 2.0, np.pi - 1e-3, np.pi - 1e-5, np.pi, np.pi + 1e-3, 4.0])
    v = t64(axes * angles[:, None], grad=True)
    _gradcheck(T.axis_angle_to_quat, v)
    _gradcheck(T.axis_angle_to_matrix, v)
    # exactly the identity: finite gradients, the analytic ones (d q_xyz / d v = I / 2, d w / d v = 0)
    zero = torch.zeros(3, dtype=torch.float64, requires_grad=True)
    jacobian = torch.autograd.functional.jacobian(T.axis_angle_to_quat, zero)
    np.testing.assert_allclose(jacobian.numpy(), np.vstack([np.eye(3) / 2, np.zeros((1, 3))]), atol=1e-12)
    identity = torch.tensor([0.0, 0.0, 0.0, 1.0], dtype=torch.float64, requires_grad=True)
    jacobian = torch.autograd.functional.jacobian(T.quat_to_axis_angle, identity)
    np.testing.assert_allclose(jacobian.numpy(), np.hstack([2 * np.eye(3), np.zeros((3, 1))]), atol=1e-12)
    # exactly a half turn (w = 0): finite gradients
    half = torch.tensor([0.0, 0.6, 0.8, 0.0], dtype=torch.float64, requires_grad=True)
    (grad,) = torch.autograd.grad(T.quat_to_axis_angle(half).square().sum(), half)
    assert torch.isfinite(grad).all()
    np.testing.assert_allclose(T.quat_to_axis_angle(half.detach()).norm().item(), np.pi, atol=1e-12)


# --------------------------------------------------------------------------- forward kinematics


@pytest.mark.parametrize("backend", ["rust", "numpy"])
def test_fk_matches_the_kernel_and_its_numpy_twin_on_random_rotations(backend):
    if backend == "rust" and not em.rust_available():
        pytest.skip("the Rust extension is not built")
    q = random_quats(6 * 22 * 8, seed=10)[: 6 * 22 * 8].reshape(6 * 8, 22, 4)
    offsets = np.random.default_rng(11).normal(size=(22, 3)) * 20
    with em.use_backend(backend):
        world, positions = ops.forward_kinematics(q, np.broadcast_to(offsets, q.shape[:2] + (3,)), BANDAI_PARENTS)
    got_q, got_p = T.forward_kinematics(t32(q).reshape(6, 8, 22, 4), t32(offsets), BANDAI_PARENTS)
    assert got_q.shape == (6, 8, 22, 4) and got_p.shape == (6, 8, 22, 3)
    np.testing.assert_allclose(got_q.reshape(-1, 22, 4).numpy(), world, atol=FLOAT32, rtol=0)  # the same signs
    scale = np.abs(positions).max()
    np.testing.assert_allclose(got_p.reshape(-1, 22, 3).numpy() / scale, positions / scale, atol=FLOAT32, rtol=0)
    m, p = T.forward_kinematics(t32(q), t32(offsets), BANDAI_PARENTS, world="matrix")
    np.testing.assert_allclose(m.numpy(), quat.to_matrix(world), atol=FLOAT32, rtol=0)


def test_fk_matches_the_kernel_on_real_clips_in_every_form(motions):
    for motion in motions:
        parents = motion.skeleton.parents
        world, positions = ops.forward_kinematics(motion.rotations, motion.translations, parents)
        scale = np.abs(positions).max()
        # per-frame translations, as the kernel takes them
        got_q, got_p = T.forward_kinematics(t32(motion.rotations), t32(motion.translations), parents)
        np.testing.assert_allclose(got_q.numpy(), world, atol=FLOAT32, rtol=0)
        np.testing.assert_allclose(got_p.numpy() / scale, positions / scale, atol=FLOAT32, rtol=0)
        # rest offsets and the hips' positions (the Bandai-Namco hips carry the motion)
        for form in ("quaternion", "6d", "matrix", "axis-angle", "euler:ZXY"):
            kind, _, order = form.partition(":")
            local = t32(encode(motion.rotations, kind, order or "ZXY"))
            _, p = T.forward_kinematics(
                local, t32(motion.skeleton.offsets), parents, t32(positions[:, 1]), root=1, form=form
            )
            np.testing.assert_allclose(p.numpy() / scale, positions / scale, atol=FLOAT32, rtol=0, err_msg=form)


def test_fk_gradients():
    q = t64(random_quats(2 * 3 * 22, seed=12)[: 2 * 3 * 22].reshape(2, 3, 22, 4), grad=True)
    offsets = t64(np.random.default_rng(13).normal(size=(22, 3)), grad=True)
    hips = t64(np.random.default_rng(14).normal(size=(2, 3, 3)), grad=True)
    _gradcheck(lambda r, o, h: T.forward_kinematics(r, o, BANDAI_PARENTS, h, root=1), q, offsets, hips)
    _gradcheck(lambda r, o: T.forward_kinematics(r, o, BANDAI_PARENTS, world="matrix"), q, offsets)
    per_frame = t64(np.random.default_rng(15).normal(size=(2, 3, 22, 3)), grad=True)
    _gradcheck(lambda r, o: T.forward_kinematics(r, o, BANDAI_PARENTS), q, per_frame)
    sixd = t64(np.random.default_rng(16).normal(size=(2, 22, 6)), grad=True)
    _gradcheck(lambda r: T.forward_kinematics(r, offsets.detach(), BANDAI_PARENTS)[1], sixd)


def test_fk_bad_inputs():
    q = torch.zeros(5, 22, 4)
    q[..., 3] = 1
    with pytest.raises(ValueError, match="argument `rotations`.*22 joints"):
        T.forward_kinematics(torch.zeros(5, 21, 4), torch.zeros(22, 3), BANDAI_PARENTS)
    with pytest.raises(ValueError, match="argument `parents`: joint 1 has parent 2"):
        T.forward_kinematics(torch.zeros(5, 3, 4), torch.zeros(3, 3), [-1, 2, 0])
    with pytest.raises(ValueError, match="argument `offsets`"):
        T.forward_kinematics(q, torch.zeros(21, 3), BANDAI_PARENTS)
    with pytest.raises(ValueError, match="argument `form`"):
        T.forward_kinematics(q, torch.zeros(22, 3), BANDAI_PARENTS, form="euler:XYX")
    with pytest.raises(ValueError, match="argument `root_positions`"):
        T.forward_kinematics(q, torch.zeros(22, 3), BANDAI_PARENTS, torch.zeros(4, 3))
    with pytest.raises(ValueError, match="argument `root`"):
        T.forward_kinematics(q, torch.zeros(22, 3), BANDAI_PARENTS, root=22)


# --------------------------------------------------------------------------- the skeleton graph


def test_the_graph_of_a_dataset(folder, motions):
    ds = load_dataset(folder)
    graph = T.skeleton_graph(folder)
    skeleton = motions[0].skeleton
    assert graph.names == skeleton.names and graph.parents.tolist() == ds.skeleton["parents"] == BANDAI_PARENTS
    # the hips move below the fixed root joint: they carry the root motion
    assert graph.moving.tolist() == [j == 1 for j in range(22)] and graph.root == 1
    still = ~graph.moving
    np.testing.assert_allclose(graph.bone_lengths[still], np.linalg.norm(skeleton.offsets, axis=-1)[still], atol=1e-3)
    np.testing.assert_allclose(graph.offsets[2:], skeleton.offsets[2:], atol=1e-3)  # read through the 6D rotations
    left, right = (skeleton.index(n) for n in ("Foot_L", "Foot_R"))
    assert graph.feet.tolist() == [[left, skeleton.index("Toes_L")], [right, skeleton.index("Toes_R")]]
    # the bones both ways, and the adjacency they make
    edges = graph.edge_index()
    assert edges.shape == (2, 2 * 21) and edges.dtype == np.int64
    pairs = {tuple(e) for e in edges.T}
    assert pairs == {(p, c) for c, p in enumerate(BANDAI_PARENTS) if p >= 0} | {
        (c, p) for c, p in enumerate(BANDAI_PARENTS) if p >= 0
    }
    a = graph.adjacency()
    np.testing.assert_array_equal(a, a.T)
    np.testing.assert_array_equal(np.argwhere(a).tolist(), sorted(map(list, pairs)))
    assert a[3].sum() == 4  # the chest: spine, neck and both shoulders
    np.testing.assert_array_equal(np.diag(graph.adjacency(self_loops=True)), np.ones(22))
    tensors = graph.tensors()
    assert tensors["edge_index"].dtype == torch.int64 and tensors["adjacency"].dtype == torch.float32
    # FK from the graph's offsets and the stored hips reproduces the stored positions
    rotations, positions = t32(ds.rotations[:500]), t32(ds.positions[:500])
    _, p = T.forward_kinematics(rotations, tensors["offsets"], graph.parents, positions[:, graph.root], root=graph.root)
    np.testing.assert_allclose(p.numpy(), positions.numpy(), atol=2e-3)  # cm, float32 storage


def test_the_graph_of_a_skeleton(motions):
    skeleton = motions[0].skeleton
    graph = T.skeleton_graph(skeleton)
    np.testing.assert_array_equal(graph.offsets, skeleton.offsets)
    assert graph.bone_lengths[0] == 0 and graph.root == 0 and graph.feet is not None
    with pytest.raises(ValueError, match="argument `source`"):
        T.skeleton_graph(42)


# --------------------------------------------------------------------------- losses


def test_finite_velocities_are_np_gradient():
    p = np.random.default_rng(17).normal(size=(3, 20, 4, 3))
    got = T.finite_velocities(torch.tensor(p), 30.0).numpy()
    np.testing.assert_allclose(got, np.gradient(p, 1 / 30.0, axis=1), atol=1e-12)
    per_window = T.finite_velocities(torch.tensor(p), torch.tensor([30.0, 60.0, 120.0])).numpy()
    np.testing.assert_allclose(per_window[2], np.gradient(p[2], 1 / 120.0, axis=0), atol=1e-12)


def test_the_velocity_loss_reads_the_stored_velocities(folder):
    ds = load_dataset(folder)
    fps = ds.clips[0]["fps"]
    clip = ds[0]
    windows = [slice(s, s + 32) for s in range(0, clip.frames - 32, 16)]
    positions = t64(np.stack([clip.positions[w] for w in windows]))
    velocities = t64(np.stack([clip.velocities[w] for w in windows]))
    typical = float(velocities.square().sum(-1).mean())
    assert T.velocity_loss(positions, velocities, fps) < 1e-6 * typical  # float32 storage alone
    assert T.velocity_loss(positions, velocities, 2 * fps) > 0.1 * typical  # a wrong rate is seen
    noisy = positions + 0.5 * torch.randn_like(positions)
    assert T.velocity_loss(noisy, velocities, fps) > 1e-3 * typical
    # frames past `valid` are left out: garbage there changes nothing
    valid = torch.full((len(windows),), 20)
    spoiled = positions.clone()
    spoiled[:, 20:] = 1e6
    assert T.velocity_loss(spoiled, velocities, fps, valid) < 1e-6 * typical
    assert T.velocity_loss(spoiled, velocities, fps) > typical


def test_the_foot_contact_loss_is_the_speed_of_planted_feet():
    # one foot of two joints moving at 3 units a frame along x, the other still; 10 fps
    positions = torch.zeros(1, 5, 4, 3, dtype=torch.float64)
    positions[0, :, 0, 0] = positions[0, :, 1, 0] = 3.0 * torch.arange(5)
    feet = [[0, 1], [2, 3]]
    down = torch.tensor([[[1, 1], [1, 1], [1, 0], [1, 0], [0, 0]]])
    # steps 0-1, 1-2, 2-3 have the left foot down at both ends (speed 30, squared 900); steps 0-1
    # the right one (speed 0): (3 * 900 + 0) / 4
    assert T.foot_contact_loss(positions, down, feet, 10.0).item() == pytest.approx(3 * 900 / 4)
    assert T.foot_contact_loss(positions, torch.zeros_like(down), feet, 10.0).item() == 0.0
    assert T.foot_contact_loss(positions, down, feet, 10.0, valid=[2]).item() == pytest.approx(900 / 2)
    with pytest.raises(ValueError, match="argument `contacts`"):
        T.foot_contact_loss(positions, down[..., :1], feet, 10.0)
    with pytest.raises(ValueError, match="argument `feet`"):
        T.foot_contact_loss(positions, down, [0, 1], 10.0)


def test_the_stored_contacts_are_where_the_feet_rest(folder):
    ds = load_dataset(folder)
    graph = T.skeleton_graph(ds)
    for clip in ds:  # one clip a window: no step across two clips
        positions, contacts = t64(clip.positions)[None], torch.tensor(clip.contacts)[None]
        assert contacts.any() and not contacts.all()
        planted = T.foot_contact_loss(positions, contacts, graph.feet, clip.record["fps"])
        flying = T.foot_contact_loss(positions, ~contacts, graph.feet, clip.record["fps"])
        assert 0 < planted < 0.05 * flying, (clip.name, float(planted), float(flying))


def test_loss_gradients():
    rng = np.random.default_rng(18)
    p = t64(rng.normal(size=(2, 6, 4, 3)), grad=True)
    v = t64(rng.normal(size=(2, 6, 4, 3)))
    contacts = torch.tensor(rng.uniform(size=(2, 6, 2)) < 0.6)
    _gradcheck(lambda x: T.velocity_loss(x, v, 30.0, valid=[6, 4]), p)
    _gradcheck(lambda x: T.foot_contact_loss(x, contacts, [[0, 1], [2, 3]], 30.0), p)
    _gradcheck(lambda x: T.finite_velocities(x, 30.0), p)


# --------------------------------------------------------------------------- packaging and docs


def test_importing_the_package_does_not_import_torch():
    code = (
        "import sys, expressive_mocap, expressive_mocap.dataset\n"
        "from expressive_mocap.dataset import load_dataset, window_batches\n"
        "assert 'torch' not in sys.modules, 'torch imported'\n"
        "import expressive_mocap.dataset.torch_ops\n"
        "assert 'torch' in sys.modules\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(REPO / "python"), os.environ.get("PYTHONPATH", "")])}
    subprocess.run([sys.executable, "-c", code], check=True, env=env)


def test_the_docs_examples_run(folder, monkeypatch):
    """docs/torch.md's Python blocks, in order in one namespace, on the three-clip dataset."""
    blocks = re.findall(r"```python\n(.*?)```", (REPO / "docs" / "torch.md").read_text(), re.S)
    assert len(blocks) >= 3
    monkeypatch.chdir(folder.parent)  # the pages name the dataset "bandai2"
    namespace: dict = {"__name__": "torch_md"}
    for k, block in enumerate(blocks):
        exec(compile(block, f"docs/torch.md (block {k + 1})", "exec"), namespace)
    # what the pages say they show: FK reproduces the stored positions, the loss reaches the rotations
    positions, b, fps = namespace["positions"].detach(), namespace["b"], namespace["fps"]
    assert float((positions - b["positions"]).abs().max()) < 5e-3
    assert torch.isfinite(namespace["loss"])
    assert T.velocity_loss(positions, b["velocities"], fps, b["valid"]) < 1e-4 * b["velocities"].square().sum(-1).mean()
    assert namespace["rotations"].grad is not None and namespace["rotations"].grad.abs().sum() > 0
    assert namespace["graph"].root == 1 and namespace["graph"].feet.tolist() == [[16, 17], [20, 21]]
