"""Forward kinematics in PyTorch: the torch twin of :func:`expressive_mocap.ops.forward_kinematics`
(the Rust kernel and its NumPy twin), batched over any leading axes and differentiable.

The joints are taken a depth level at a time (every joint of a level at once, each from its
parent in the level before), and within a level the whole batch at once: a skeleton of depth 8
is 8 steps however many windows and frames. The matrices are held component-major
(``[3, 3, joints, frames]``) so that each step is a few element-wise products of long contiguous
rows rather than many tiny 3x3 matrix products.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import torch

from ...errors import ArgumentError
from .rotations import FORMS, form_size, matrix_to_quat, quat_to_matrix, to_quat


@lru_cache(maxsize=64)
def _levels(parents: tuple[int, ...]) -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Per depth level: its joints, and the place of each one's parent among the level before's."""
    depth = np.zeros(len(parents), dtype=np.int64)
    for j, p in enumerate(parents):
        if not -1 <= p < j:
            raise ArgumentError(
                f"argument `parents`: joint {j} has parent {p}: parents must be -1 (root) or an earlier joint"
            )
        depth[j] = 0 if p < 0 else depth[p] + 1
    levels = []
    previous = np.zeros(0, dtype=np.int64)
    for d in range(int(depth.max()) + 1 if len(parents) else 0):
        joints = np.flatnonzero(depth == d)
        place = np.searchsorted(previous, [parents[j] for j in joints]) if d else np.zeros(0, dtype=np.int64)
        levels.append((joints, place))
        previous = joints
    return tuple(levels)


def parents_tuple(parents) -> tuple[int, ...]:
    """``parents`` (a sequence, array or tensor of ints ``[J]``) as a tuple of ints, checked."""
    if isinstance(parents, torch.Tensor):
        parents = parents.detach().cpu().numpy()
    array = np.asarray(parents)
    if array.ndim != 1 or (array.size and array.dtype.kind not in "iu"):
        raise ArgumentError(
            f"argument `parents`: expected integers [J], got {array.dtype} of shape {list(array.shape)}"
        )
    return tuple(int(p) for p in array)


def infer_form(rotations: torch.Tensor, joints: int) -> str:
    """The form of local rotations ``[..., J, n]`` or ``[..., J, 3, 3]`` from their shape: the
    last axis 4 (quaternion), 6 (6d), 9 (matrix, row after row), ``3, 3`` after the joints
    (matrix) or 3 (axis-angle)."""
    shape = tuple(rotations.shape)
    if len(shape) >= 3 and shape[-3:] == (joints, 3, 3):
        return "matrix3x3"
    if len(shape) >= 2 and shape[-2] == joints:
        for form, n in FORMS.items():
            if shape[-1] == n:
                return form
    raise ArgumentError(
        f"argument `rotations`: expected [..., {joints}, n] with n one of 4 (quaternion), 6 (6d), 9 (matrix), "
        f"3 (axis-angle), or [..., {joints}, 3, 3], for the {joints} joints of `parents`; got {list(shape)}"
    )


def _quaternions(rotations: torch.Tensor, form: str, joints: int) -> tuple[torch.Tensor, tuple[int, ...]]:
    """Unit local quaternions ``[N, J, 4]`` (N: the leading axes flattened) and the leading shape."""
    if form == "matrix3x3":
        batch = tuple(rotations.shape[:-3])
        return matrix_to_quat(rotations.reshape(-1, joints, 3, 3)), batch
    batch = tuple(rotations.shape[:-2])
    flat = rotations.reshape(-1, joints, rotations.shape[-1])
    if form == "quaternion":
        return flat, batch  # normalised component-major, where it is cheap
    return to_quat(flat, form), batch


def forward_kinematics(
    rotations: torch.Tensor,
    offsets,
    parents,
    root_positions: torch.Tensor | None = None,
    *,
    root: int = 0,
    form: str | None = None,
    world: str = "quaternion",
) -> tuple[torch.Tensor, torch.Tensor]:
    """World rotations and positions ``[..., J, 3]`` of a skeleton from its local rotations.

    ``rotations``: each joint's rotation relative to its parent, ``[..., J, 4]`` quaternions
    (x, y, z, w; normalised first, so a network's raw output will do), ``[..., J, 6]`` 6D,
    ``[..., J, 9]`` or ``[..., J, 3, 3]`` matrices, ``[..., J, 3]`` rotation vectors; ``form``
    names it when the shape does not (one of ``"quaternion"``, ``"6d"``, ``"matrix"``,
    ``"axis-angle"``). ``offsets``: each joint's translation from its parent, ``[J, 3]`` (the rest
    offsets) or ``[..., J, 3]`` (per frame, broadcast against the rotations' leading axes); a
    root's is its position. ``parents [J]``: each joint after its parent, roots -1.
    ``root_positions [..., 3]``: the world position of joint ``root`` (default: joint 0),
    overriding what its offset gives; its descendants follow it. For a skeleton whose hips carry
    the motion below a fixed root joint (the Bandai-Namco one), pass the hips' positions with
    ``root=`` the hips (:attr:`~expressive_mocap.dataset.torch_ops.SkeletonGraph.root`).

    Returns ``(world_rotations, positions)``: ``[..., J, 4]`` quaternions (``world="quaternion"``,
    the default: the very products the package's kernel forms, ``Q_j = Q_parent q_j``, so the same
    signs) or ``[..., J, 3, 3]`` matrices (``world="matrix"``), and ``[..., J, 3]`` positions,
    ``p_j = p_parent + Q_parent o_j``. Other forms are turned into quaternions first.
    """
    if not isinstance(rotations, torch.Tensor) or not rotations.is_floating_point():
        raise ArgumentError(
            f"argument `rotations`: expected a floating-point torch.Tensor, got {type(rotations).__name__}"
        )
    if world not in ("matrix", "quaternion"):
        raise ArgumentError(f"argument `world`: expected 'matrix' or 'quaternion', got {world!r}")
    parent_list = parents_tuple(parents)
    joints = len(parent_list)
    if joints == 0:
        raise ArgumentError("argument `parents`: a skeleton needs at least one joint")
    _levels(parent_list)  # checks the order
    if form is None:
        form = infer_form(rotations, joints)
    elif form == "matrix" and tuple(rotations.shape[-3:]) == (joints, 3, 3):
        form = "matrix3x3"
    elif tuple(rotations.shape[-2:]) != (joints, size := form_size(form)):
        raise ArgumentError(
            f"argument `rotations`: a {form} is {size} values, expected [..., {joints}, {size}], "
            f"got {list(rotations.shape)}"
        )
    local, batch = _quaternions(rotations, form, joints)
    frames = local.shape[0]
    dtype, device = rotations.dtype, rotations.device
    offsets = torch.as_tensor(offsets, dtype=dtype, device=device)
    if offsets.dim() < 2 or tuple(offsets.shape[-2:]) != (joints, 3):
        raise ArgumentError(
            f"argument `offsets`: expected [J, 3] or [..., J, 3] with J = {joints}, got {list(offsets.shape)}"
        )
    if offsets.dim() == 2:
        offset = offsets.t().unsqueeze(-1)  # [3, J, 1]: one row a joint, broadcast over frames
    else:
        offset = _leading("offsets", offsets, batch, 2).reshape(frames, joints, 3).permute(2, 1, 0)
    if not 0 <= root < joints:
        raise ArgumentError(f"argument `root`: expected a joint index in [0, {joints}), got {root}")
    placed = None
    if root_positions is not None:
        root_positions = torch.as_tensor(root_positions, dtype=dtype, device=device)
        if root_positions.shape[-1:] != (3,):
            raise ArgumentError(f"argument `root_positions`: expected [..., 3], got {list(root_positions.shape)}")
        placed = _leading("root_positions", root_positions, batch, 1).reshape(frames, 3).t()  # [3, N]

    # Joint by joint, each component a contiguous row of the frames: a few dozen element-wise
    # operations on rows of N values a joint, fused where torch has the fused form (addcmul);
    # cheaper than gathering whole depth levels, or than batches of 3x3 matrix products.
    qs = local.permute(2, 1, 0).contiguous()  # [4, J, N]
    if offset.shape[-1] == 1 and not offset.requires_grad:
        rows = offset[..., 0].t().tolist()  # plain numbers: the fast scalar forms
        numbers = True
    else:
        rows = [(offset[0, j], offset[1, j], offset[2, j]) for j in range(joints)]
        numbers = False
    quats: list[tuple[torch.Tensor, ...]] = []
    points: list[tuple[torch.Tensor, ...]] = []
    for j, p in enumerate(parent_list):
        x, y, z, w = qs[0, j], qs[1, j], qs[2, j], qs[3, j]
        if form == "quaternion":  # normalised here, a joint's rows at a time (no large temporaries)
            scale = torch.rsqrt((x * x).addcmul_(y, y).addcmul_(z, z).addcmul_(w, w))
            x, y, z, w = x * scale, y * scale, z * scale, w * scale
        ox, oy, oz = rows[j]
        if p < 0:
            quat = (x, y, z, w)
            point = tuple(torch.full_like(x, o) if numbers else o.expand(frames) for o in (ox, oy, oz))
        else:
            px, py, pz, pw = quats[p]
            quat = (
                (pw * x).addcmul_(px, w).addcmul_(py, z).addcmul_(pz, y, value=-1),
                (pw * y).addcmul_(px, z, value=-1).addcmul_(py, w).addcmul_(pz, x),
                (pw * z).addcmul_(px, y).addcmul_(py, x, value=-1).addcmul_(pz, w),
                (pw * w).addcmul_(px, x, value=-1).addcmul_(py, y, value=-1).addcmul_(pz, z, value=-1),
            )
            # p_parent + o + w t + u x t, with t = 2 u x o (u, w: the parent's quaternion)
            tx, ty, tz = (
                _cross2(py, pz, oz, oy, numbers),
                _cross2(pz, px, ox, oz, numbers),
                _cross2(px, py, oy, ox, numbers),
            )
            bx, by, bz = points[p]
            point = (
                (bx + ox).addcmul_(pw, tx).addcmul_(py, tz).addcmul_(pz, ty, value=-1),
                (by + oy).addcmul_(pw, ty).addcmul_(pz, tx).addcmul_(px, tz, value=-1),
                (bz + oz).addcmul_(pw, tz).addcmul_(px, ty).addcmul_(py, tx, value=-1),
            )
        if placed is not None and j == root:
            point = (placed[0], placed[1], placed[2])
        quats.append(quat)
        points.append(point)
    # Stacked component-major (a fast copy), handed back as a view in the caller's layout.
    world_q = torch.stack([c for quat in quats for c in quat]).t().reshape(*batch, joints, 4)
    positions = torch.stack([c for point in points for c in point]).t().reshape(*batch, joints, 3)
    if world == "matrix":
        return quat_to_matrix(world_q), positions
    return world_q, positions


def _cross2(a: torch.Tensor, b: torch.Tensor, ob, oa, numbers: bool) -> torch.Tensor:
    """``2 (a ob - b oa)``: a component of ``2 u x o`` (``ob``, ``oa`` numbers or rows)."""
    if numbers:
        return torch.add(a * (2.0 * ob), b, alpha=-2.0 * oa)
    return 2.0 * (a * ob - b * oa)


def _leading(name: str, value: torch.Tensor, batch: tuple[int, ...], trailing: int) -> torch.Tensor:
    """``value`` broadcast to the rotations' leading axes ``batch`` (its last ``trailing`` axes kept)."""
    try:
        return value.expand(*batch, *value.shape[value.dim() - trailing :])
    except RuntimeError:
        raise ArgumentError(
            f"argument `{name}`: its leading axes {list(value.shape[: value.dim() - trailing])} do not broadcast to "
            f"the rotations' {list(batch)}"
        ) from None


__all__ = ["forward_kinematics", "infer_form", "parents_tuple"]
