"""Twin of ``rust/retarget.rs``: retargeting's transfer of a pose, vectorised over frames."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat

_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def _turned(turn: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """World ``rotations`` expressed in axes turned by ``turn``: ``turn * q * turn^-1``."""
    if np.allclose(turn, _IDENTITY, rtol=0, atol=1e-15):  # Y up, facing +Z: nothing to turn
        return rotations
    return quat.mul(quat.mul(turn, rotations), quat.conjugate(turn))


def _check(plan, source_joints: int) -> None:
    roles, joints = len(plan.source), len(plan.parents)
    for j, p in enumerate(np.asarray(plan.parents).tolist()):
        if not -1 <= p < j:
            raise ArgumentError(
                f"argument `parents`: joint {j} has parent {p}: parents must be -1 (root) or an earlier joint"
            )
    lengths = {
        "target": (np.size(plan.target), roles),
        "aligns": (np.size(plan.aligns), 4 * roles),
        "starts": (np.size(plan.starts), len(plan.swung)),
        "ends": (np.size(plan.ends), len(plan.swung)),
        "rest_lines": (np.size(plan.rest_lines), 3 * len(plan.swung)),
        "tops": (np.size(plan.tops), len(plan.shared)),
        "bottoms": (np.size(plan.bottoms), len(plan.shared)),
        "shares": (np.size(plan.shares), len(plan.shared)),
        "copied": (np.size(plan.copied), len(plan.held)),
        "reference": (np.size(plan.reference), 4 * joints),
    }
    for name, (got, expected) in lengths.items():
        if got != expected:
            raise ArgumentError(f"argument `plan`: {name} has {got} values, expected {expected}")
    bounds = {"source": source_joints, "starts": source_joints, "ends": source_joints, "swung": roles}
    bounds.update(dict.fromkeys(("target", "shared", "tops", "bottoms", "held", "copied"), joints))
    for name, bound in bounds.items():
        values = np.asarray(getattr(plan, name))
        low = -1 if name == "copied" else 0
        bad = values[(values < low) | (values >= bound)]
        if len(bad):
            raise ArgumentError(f"argument `plan`: {name} holds {bad[0]}, not a joint or role below {bound}")


def retarget_transfer(world: np.ndarray, positions: np.ndarray, plan) -> np.ndarray:
    """The target's local rotations ``[F, Jt, 4]`` from the source's world rotations ``world
    [F, Js, 4]`` and positions ``positions [F, Js, 3]`` along ``plan`` (see ``rust/retarget.rs``)."""
    if world.ndim != 3 or world.shape[-1] != 4:
        raise ArgumentError(f"argument `world`: expected shape [F, J, 4], got {list(world.shape)}")
    if positions.shape != world.shape[:2] + (3,):
        raise ArgumentError(
            f"argument `positions`: expected shape [{world.shape[0]}, {world.shape[1]}, 3], got {list(positions.shape)}"
        )
    _check(plan, world.shape[1])
    turn_s, turn_t = np.asarray(plan.turn_source, float), np.asarray(plan.turn_target, float)
    roles = _turned(turn_s, world[:, plan.source])  # canonical axes
    if len(plan.swung):
        # Each swung role turned so that its bone lies where the source's positions put it.
        lines = quat.rotate(turn_s, positions[:, plan.ends] - positions[:, plan.starts])
        predicted = quat.rotate(roles[:, plan.swung], plan.rest_lines)
        roles[:, plan.swung] = quat.mul(quat.between(predicted, lines), roles[:, plan.swung])
    frames, joints = len(world), len(plan.parents)
    out = np.empty((frames, joints, 4))
    out[:] = _IDENTITY  # a joint the plan leaves out
    out[:, plan.target] = quat.mul(roles, plan.aligns)
    # Unmapped joints turn with the mapped ones, as changes from the target's reference pose.
    reference = np.asarray(plan.reference, dtype=np.float64)
    if len(plan.shared):
        top = quat.mul(out[:, plan.tops], quat.conjugate(reference[plan.tops]))
        bottom = quat.mul(out[:, plan.bottoms], quat.conjugate(reference[plan.bottoms]))
        turn = quat.power(quat.mul(quat.conjugate(top), bottom), plan.shares)
        out[:, plan.shared] = quat.mul(quat.mul(top, turn), reference[plan.shared])
    if len(plan.held):
        copied = np.asarray(plan.copied)
        ancestor = quat.mul(out[:, np.maximum(copied, 0)], quat.conjugate(reference[np.maximum(copied, 0)]))
        change = np.where((copied >= 0)[:, None], ancestor, _IDENTITY)
        out[:, plan.held] = quat.mul(change, reference[plan.held])
    out = _turned(quat.conjugate(turn_t), out)  # the target's axes
    parents = np.asarray(plan.parents)
    local = out.copy()
    has_parent = parents >= 0
    local[:, has_parent] = quat.mul(quat.conjugate(out[:, parents[has_parent]]), out[:, has_parent])
    return local


__all__ = ["retarget_transfer"]
