"""Joint positions fitted as a motion on the layout's own skeleton (:func:`fit_layout`), the
first step of :func:`~.fit.fit_positions`.

- **The skeleton**: every bone's length is its median over the frames; the rest pose is a T-pose
  (Y up, facing +Z: legs down, arms out to the side, spine and neck up, feet forward, pitched as
  the data's feet are where they stand), but for the joints leaving the hips and the chest, which
  keep the median place the data gives them there (hip joints, clavicles, the neck).
- **Rotations**: the hips and the chest as the rigid bodies that best carry their children
  (least squares; by the lines across them and up the spine where the children do not fix one);
  a limb segment, clavicle, foot or neck by its bone (the line to its child) and the way the
  positions say it faces (:func:`~.twist.facing`: the plane an elbow or knee bends in, where the
  foot points, the chest's forward); where a layout has no toes, a thigh or shin by its knee's
  plane, the hips' forward when the leg is straight. Each joint's world rotation takes its frame
  in the rest pose onto its frame in the frame's positions, so every bone points where the
  positions put it. The ways joints face are smoothed over a Gaussian of one frame at 30 fps (no
  flips where noise turns a nearly straight limb's plane). Other joints turn by the shortest arc
  from their parent's rotation; the ends (a head, a wrist without a hand joint) keep their
  parent's.
- The hips' path is the root's positions.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..body.jointmap import JointMap, find_joint_map
from ..motion import Motion, Skeleton, spread_frames
from ..rotations import quat
from . import twist
from .layouts import Layout, layout_of
from .rig import _frame_vectors, _orthonormal

_ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation")
_CHANNELS = ("Zrotation", "Yrotation", "Xrotation")
_ARM = ("clavicle", "upper_arm", "forearm", "hand")
_FOOT_DOWN = np.array([0.0, -0.4, 1.0]) / np.hypot(0.4, 1.0)  # a foot's rest bone: forward, a little down


def full_map(jmap: JointMap, names: tuple[str, ...] | None = None) -> dict[str, object]:
    """``jmap`` as a user map (role -> joint name, ``spine`` -> names) of a skeleton of ``names``
    (default: the map's own)."""
    names = jmap.names if names is None else names
    out: dict[str, object] = {role: names[j] for role, j in jmap.joints.items()}
    if jmap.spine:
        out["spine"] = [names[j] for j in jmap.spine]
    return out


def own_names(layout: Layout) -> tuple[str, ...]:
    """The fitted skeleton's joint names: the layout's, but in a ``fit:`` namespace where they are
    the Bandai-Namco skeleton's (positions of that skeleton), whose names tell retargeting that
    its reference pose is a walk's, not the T-pose rest the fit builds."""
    from ..body.canonical import bandai_like_skeleton

    bandai = bandai_like_skeleton()
    if layout.names == bandai.names and layout.parents == tuple(bandai.parents.tolist()):
        return tuple(f"fit:{n}" for n in layout.names)
    return layout.names


def _children(parents: np.ndarray) -> list[list[int]]:
    out: list[list[int]] = [[] for _ in parents]
    for j, p in enumerate(parents[1:], 1):
        out[p].append(j)
    return out


class _Plan(NamedTuple):
    """How each joint's rotation is read: ``kinds[j]`` is ``frame`` (hips, chest), ``facing``
    (:func:`~.twist.facing`), ``hinge`` (a limb without toes), ``swing`` or ``end``; ``bones[j]``
    the child whose line is its bone (-1: none)."""

    kinds: list[str]
    bones: list[int]
    roles: dict[int, str]


def _plan(parents: np.ndarray, jmap: JointMap) -> _Plan:
    roles = {j: r for r, j in jmap.joints.items()}
    children = _children(parents)
    kinds, bones = [], []
    above_hips = set()
    j = int(parents[jmap["hips"]])
    while j >= 0:
        above_hips.add(j)
        j = int(parents[j])
    for j, kids in enumerate(children):
        role = roles.get(j)
        nxt = kids[0] if len(kids) == 1 else -1
        part = role.split("_", 1)[1] if role and role.startswith(("left_", "right_")) else role
        if j in above_hips:  # a root below which the hips move (their own path): it stays unturned
            kinds.append("end")
        elif role in ("hips", "chest"):
            kinds.append("frame")
        elif not kids:
            kinds.append("end")
        elif nxt >= 0 and role and twist.readable(jmap, role) and part not in ("head", "toes"):
            kinds.append("facing")
        elif (
            nxt >= 0
            and role
            and part in twist.LIMBS
            and all(f"{role.split('_')[0]}_{p}" in jmap for p in twist.LIMBS[part])
        ):
            kinds.append("hinge")
        else:
            kinds.append("swing")
        bones.append(nxt)
    return _Plan(kinds, bones, roles)


def _frame(points: np.ndarray, jmap: JointMap, plan: _Plan, j: int, sigma: float = 0.0) -> np.ndarray:
    """Joint ``j``'s frame ``[..., 3, 3]`` (columns) in the positions ``[..., J, 3]`` (``kinds``
    ``frame``, ``facing`` or ``hinge``): its line and the way it faces, that smoothed over frames
    (``sigma`` frames; 0: not)."""
    role, kind = plan.roles[j], plan.kinds[j]
    if kind == "frame":
        line, second = _frame_vectors(points, jmap, role, jmap)
    else:
        line = points[..., plan.bones[j], :] - points[..., j, :]
        if kind == "facing":
            second = twist.facing(points, jmap, role, line)
        else:
            side, part = role.split("_", 1)
            limb = twist.LIMBS[part]
            hinge, sure = twist._hinge(points, jmap, side, limb)
            if limb[0] == "upper_arm":
                straight = twist.chest_forward(points, jmap)
            else:
                hips = _orthonormal(*_frame_vectors(points, jmap, "hips", jmap))
                straight = hips[..., 2]
            bent = twist._square_to(quat.cross(hinge, line), line)
            second = twist._unit(sure * bent + (1.0 - sure) * twist._square_to(straight, line))
    if sigma > 0 and second.ndim > 1 and len(second) > 1:
        from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

        second = gaussian_filter1d(second, sigma, axis=0, mode="nearest")
    return _orthonormal(line, second)


def _rest_direction(j: int, plan: _Plan, jmap: JointMap, rest_dirs: dict[int, np.ndarray], flat: dict[int, np.ndarray]):
    """The T-pose direction of the bones leaving joint ``j`` (see the module's notes; ``flat``:
    the feet's, :func:`_flat_feet`)."""
    role = plan.roles.get(j)
    side, part = role.split("_", 1) if role and role.startswith(("left_", "right_")) else ("", role)
    if part in _ARM:
        return np.array([1.0 if side == "left" else -1.0, 0.0, 0.0])
    if part in ("upper_leg", "lower_leg"):
        return np.array([0.0, -1.0, 0.0])
    if part == "foot":
        return flat.get(j, _FOOT_DOWN)
    if part == "toes":
        return np.array([0.0, 0.0, 1.0])
    if part in ("neck", "head") or j in jmap.spine or role == "hips":
        return np.array([0.0, 1.0, 0.0])
    return rest_dirs.get(j, np.array([0.0, 1.0, 0.0]))  # an unmapped joint: straight on


def _flat_feet(positions: np.ndarray, jmap: JointMap, plan: _Plan) -> dict[int, np.ndarray]:
    """Per ankle with a bone to the toes, that bone's direction in a T-pose standing flat: forward,
    pitched as the data's is where the toes are lowest (the lowest fifth of their heights: the foot
    on the floor). Retargeting carries a foot by its flat stance; a rest foot pitched otherwise
    than the data's flat one tipped the target's toes by the difference."""
    out = {}
    for side in ("left", "right"):
        role = f"{side}_foot"
        j = jmap.joints.get(role, -1)
        if j < 0 or plan.bones[j] < 0:
            continue
        bone = positions[:, plan.bones[j]] - positions[:, j]
        low = positions[:, plan.bones[j], 1] <= np.percentile(positions[:, plan.bones[j], 1], 20)
        pitch = np.median(np.arcsin(np.clip(bone[low, 1] / np.linalg.norm(bone[low], axis=-1), -1.0, 1.0)))
        out[j] = np.array([0.0, np.sin(pitch), np.cos(pitch)])
    return out


SAMPLED = 256


def fit_skeleton(positions: np.ndarray, layout: Layout) -> tuple[Skeleton, dict[str, object], _Plan]:
    """The layout's skeleton built from ``positions [F, J, 3]`` (Y up), the joint map it is read
    with (a user map naming every role) and the plan of its rotations. Its medians are over at
    most :data:`SAMPLED` frames spread over the clip (a median over a clip's evenly spread frames is
    as good: a fifth of the time of a 1,000-frame fit went to them)."""
    positions = positions[spread_frames(len(positions), SAMPLED)]
    parents = np.array(layout.parents)
    lengths = np.median(np.linalg.norm(positions[:, 1:] - positions[:, parents[1:]], axis=-1), axis=0)
    jmap = find_joint_map(draft(positions, layout), layout.joint_map)
    plan = _plan(parents, jmap)
    children = _children(parents)
    # The children of the hips and chest: their median place in the frame of their parent (the
    # lines across and up), then in the rotations that place them best (:func:`_rigid`).
    framed: dict[int, np.ndarray] = {}
    for j, kind in enumerate(plan.kinds):
        if kind == "frame":
            carried = _carried_by(j, children, lengths, plan.roles)
            frames = _frame(positions, jmap, plan, j)  # [F, 3, 3]
            lines = positions[:, carried] - positions[:, j, None]
            local = np.median(np.einsum("fji,fcj->fci", frames, lines), axis=0)
            if _rigid_ok(local):
                local = np.median(quat.rotate(quat.conjugate(_rigid(local, lines))[:, None], lines), axis=0)
            for c, place in zip(carried, local):  # a grandchild's offset: from its parent at the joint
                framed[c] = place - (framed[parents[c]] if parents[c] != j else 0.0)
    flat = _flat_feet(positions, jmap, plan)
    offsets = np.zeros((len(parents), 3))
    rest_dirs: dict[int, np.ndarray] = {}
    for c in range(1, len(parents)):
        p = parents[c]
        if c in framed:
            offsets[c] = framed[c]
        else:
            offsets[c] = _rest_direction(p, plan, jmap, rest_dirs, flat) * lengths[c - 1]
        norm = np.linalg.norm(offsets[c])
        rest_dirs[c] = offsets[c] / norm if norm > 1e-9 else rest_dirs.get(p, np.array([0.0, 1.0, 0.0]))
    names = own_names(layout)
    skeleton = Skeleton(names, parents, offsets, _channels(parents, jmap["hips"]))
    return skeleton, full_map(jmap, names), plan


def _carried_by(j: int, children: list[list[int]], lengths: np.ndarray, roles: dict[int, str]) -> list[int]:
    """The joints whose median place the hips or chest ``j`` carries: its children, and past a
    child of no role that sits at the joint (CMU's hip joints hang from such joints at the hips),
    that child's children too."""
    out = []
    for c in children[j]:
        out.append(c)
        if c not in roles and lengths[c - 1] <= 1e-3 * np.median(lengths):
            out.extend(children[c])
    return out


def _rigid_ok(rest: np.ndarray) -> bool:
    """Whether rest offsets ``[C, 3]`` fix a rotation: two children or more, not all on a line."""
    return len(rest) >= 2 and np.linalg.matrix_rank(rest, tol=1e-6 * max(np.abs(rest).max(), 1e-12)) >= 2


def _rigid(rest: np.ndarray, now: np.ndarray) -> np.ndarray:
    """The rotations ``[F, 4]`` that best turn the offsets ``rest [C, 3]`` onto ``now [F, C, 3]``
    (least squares: Kabsch's). The hips' and chest's children move with them as one body, where
    the line up the spine bends with it."""
    covariance = np.einsum("ci,fcj->fij", rest, now)
    u, _, vt = np.linalg.svd(covariance)
    turn = np.swapaxes(vt, -1, -2) @ np.swapaxes(u, -1, -2)
    flip = np.linalg.det(turn) < 0  # a reflection: the least-squares rotation flips the weakest axis
    vt[flip, 2] *= -1
    turn[flip] = np.swapaxes(vt[flip], -1, -2) @ np.swapaxes(u[flip], -1, -2)
    return quat.from_matrix(turn)


def _channels(parents: np.ndarray, hips: int) -> tuple[tuple[str, ...], ...]:
    """Position and rotation channels for the root and the hips, rotations for the others."""
    return tuple(_ROOT_CHANNELS if j in (0, hips) else _CHANNELS for j in range(len(parents)))


def _rest_positions(offsets: np.ndarray, parents: np.ndarray) -> np.ndarray:
    out = np.zeros_like(offsets)
    for j in range(1, len(parents)):
        out[j] = out[parents[j]] + offsets[j]
    return out


def fit_layout(positions: np.ndarray, layout: Layout | str, fps: float, *, smooth: float = 1.0) -> Motion:
    """The motion on the layout's own skeleton whose joints follow ``positions [F, J, 3]`` (Y up;
    see the module's notes). ``smooth``: the Gaussian the ways joints face are smoothed over,
    in frames at 30 fps (0: none)."""
    layout = layout_of(layout) if isinstance(layout, str) else layout
    skeleton, user_map, plan = fit_skeleton(positions, layout)
    jmap = find_joint_map(skeleton, user_map)
    parents = skeleton.parents
    rest = _rest_positions(skeleton.offsets, parents)
    children = _children(parents)
    sigma = smooth * fps / 30.0
    frames, joints = positions.shape[:2]
    world = np.zeros((frames, joints, 4))
    identity = np.array([0.0, 0.0, 0.0, 1.0])
    for j, kind in enumerate(plan.kinds):
        above = world[:, parents[j]] if j else np.broadcast_to(identity, (frames, 4))
        world[:, j] = above
        with np.errstate(invalid="ignore", divide="ignore"):  # zero-length bones: their parent's turn
            if kind == "frame" and _rigid_ok(skeleton.offsets[children[j]]):
                lines = positions[:, children[j]] - positions[:, j, None]
                world[:, j] = quat.smooth(_rigid(skeleton.offsets[children[j]], lines), sigma)
            elif kind in ("frame", "facing", "hinge"):
                then = _frame(rest, jmap, plan, j)
                if np.isfinite(then).all():
                    world[:, j] = quat.from_matrix(_frame(positions, jmap, plan, j, sigma) @ then.T)
            elif kind == "swing":
                then = np.mean(skeleton.offsets[children[j]], axis=0)
                now = np.mean(positions[:, children[j]], axis=1) - positions[:, j]
                if np.linalg.norm(then) > 1e-9:
                    world[:, j] = quat.mul(quat.between(quat.rotate(above, then), now), above)
        bad = ~np.isfinite(world[:, j]).all(axis=-1)
        world[bad, j] = above[bad]
    world = _continuous(world)
    local = world.copy()
    local[:, 1:] = quat.mul(quat.conjugate(world[:, parents[1:]]), world[:, 1:])
    translations = np.broadcast_to(skeleton.offsets, (frames, joints, 3)).copy()
    translations[:, 0] = positions[:, 0]
    hips = jmap["hips"]
    if hips:  # under a root of its own: the hips' path from it (the joints above stay unturned)
        translations[:, hips] = positions[:, hips] - positions[:, parents[hips]]
    return Motion(skeleton, quat.normalize(local), translations, 1.0 / fps)


def _continuous(q: np.ndarray) -> np.ndarray:
    """Quaternions ``[F, ..., 4]`` each put on its predecessor's hemisphere (the same rotations)."""
    flips = np.cumprod(np.where(np.sum(q[1:] * q[:-1], axis=-1) < 0, -1.0, 1.0), axis=0)
    out = q.copy()
    out[1:] *= flips[..., None]
    return out


def draft(points: np.ndarray, layout: Layout) -> Skeleton:
    """A skeleton whose rest is ``points``' first frame: enough to read the layout's joint map."""
    parents = np.array(layout.parents)
    offsets = np.vstack([np.zeros(3), points[0, 1:] - points[0, parents[1:]]])
    return Skeleton(layout.names, parents, offsets, (_ROOT_CHANNELS,) * len(parents))


__all__ = ["SAMPLED", "draft", "fit_layout", "fit_skeleton", "full_map", "own_names"]
