"""Twin of ``rust/decouple.rs``: the per-joint algebra of decoupling, in NumPy."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat


def _check(name: str, first: np.ndarray, second: np.ndarray) -> None:
    if first.ndim != 3 or first.shape[-1] != 4 or first.shape != second.shape:
        raise ArgumentError(
            f"argument `{name}`: expected shape {list(first.shape)} (quaternions [F, J, 4]), got {list(second.shape)}"
        )


def decouple_rotations(original: np.ndarray, body: np.ndarray, gain: float = 2.0, exponent: float = 4.0):
    """``E = O B^-1``, ``A = clip((tanh(angle(E)) gain)^exponent, 0, 1)``, ``E* = E^A``,
    ``B' = E*^-1 O``: returns ``(E*, B', A)``."""
    _check("body", original, body)
    return split_rotations(original, body, gain, exponent, np.ones(original.shape[1]), 0.0, 0.0)


def split_rotations(
    original: np.ndarray,
    body: np.ndarray,
    gain: float,
    exponent: float,
    scale: np.ndarray,
    body_sigma: float,
    activity_sigma: float,
    trunk_joints=(),
    trunk_bones=(),
    trunk_scale: float = 1.0,
    arm_parents=(),
    arm_joints=(),
):
    """One clip's ``(E*, B', A)`` with ``B`` smoothed over ``body_sigma`` frames (each joint's
    quaternions on their predecessor's hemisphere, filtered, normalised) and ``A``, read from
    ``angle(O B^-1) / scale [J]``, over ``activity_sigma`` frames (Gaussians, the ends held; 0: none).
    ``trunk_joints`` (the chain from the hips up; empty: none) are at least as active as the
    angle between the chain's trunk lines (the ``trunk_bones [n, 3]`` each joint carries, summed
    as the chain turns them) in ``O`` and ``B``, divided by ``trunk_scale``, reads. ``arm_joints``
    (empty: none; parents before children, ``arm_parents`` the skeleton's) are filtered in world
    axes (:func:`hang_limbs`)."""
    _check("body", original, body)
    if np.shape(scale) != original.shape[1:2]:
        raise ArgumentError(
            f"argument `scale`: expected shape {list(original.shape[1:2])} (one value per joint of `original`), "
            f"got {list(np.shape(scale))}"
        )
    for name, value in (("gain", gain), ("exponent", exponent), *(("scale", v) for v in np.ravel(scale))):
        if not (np.isfinite(value) and value > 0):
            raise ArgumentError(f"argument `{name}`: must be a positive number, got {value}")
    for name, value in (("body_sigma", body_sigma), ("activity_sigma", activity_sigma)):
        if not (np.isfinite(value) and value >= 0):
            raise ArgumentError(f"argument `{name}`: must be a number >= 0, got {value}")
    trunk_joints = [int(j) for j in trunk_joints]
    bones = np.asarray(trunk_bones, dtype=np.float64).reshape(-1, 3)
    _check_trunk(trunk_joints, bones, trunk_scale, original.shape[1])
    limbs = [int(j) for j in arm_joints]
    parents = [int(p) for p in arm_parents]
    if limbs:
        _check_arms(parents, limbs, original.shape[1])
    smooth = len(original) > 1
    if body_sigma > 0 and smooth:
        body = quat.smooth(body, body_sigma)
    expressive = quat.mul(original, quat.conjugate(body))  # E = O B^-1
    activity = np.clip((np.tanh(quat.angle(expressive) / scale) * gain) ** exponent, 0.0, 1.0)
    if trunk_joints:
        lean = trunk_lean(original, body, trunk_joints, bones)
        chain = np.clip((np.tanh(lean / trunk_scale) * gain) ** exponent, 0.0, 1.0)
        activity[:, trunk_joints] = np.maximum(activity[:, trunk_joints], chain[:, None])
    if activity_sigma > 0 and smooth:
        from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

        activity = np.clip(gaussian_filter1d(activity, activity_sigma, axis=0, mode="nearest"), 0.0, 1.0)
    filtered = quat.power(expressive, activity)  # E* = E^A
    recovered = quat.mul(quat.conjugate(filtered), original)  # B' = E*^-1 O
    if limbs:
        hang_limbs(original, body, activity, filtered, recovered, parents, limbs)
    return filtered, recovered, activity


def hang_limbs(original, body, activity, expressive, recovered, parents: list[int], limbs: list[int]) -> None:
    """Refilter ``limbs`` (in order) in world axes, in place: ``E_w = W_O W_B^-1`` (the limb's world
    rotation in the original and in the body mechanics), ``E*_w = E_w^A`` with the limb's
    activity; the limb's ``B'`` made local below the ``B'`` above it so that its world rotation is
    ``E*_w^-1 W_O`` (for world changes up to WORLD_FULL; beyond, less and less: :func:`world_trust`),
    and its ``E* = O B'^-1``. A relaxed arm then hangs in the world as the actor's does, whatever
    the body mechanics do to the trunk above it."""
    for limb in limbs:
        seen = _world(original, parents, limb)
        change = quat.mul(seen, quat.conjugate(_world(body, parents, limb)))
        above = _world(recovered, parents, parents[limb])
        hung = quat.mul(quat.conjugate(above), quat.mul(quat.conjugate(quat.power(change, activity[:, limb])), seen))
        own = recovered[:, limb]
        trust = world_trust(quat.angle(change))
        local = quat.normalize(quat.mul(own, quat.power(quat.mul(quat.conjugate(own), hung), trust)))
        recovered[:, limb] = local
        expressive[:, limb] = quat.mul(original[:, limb], quat.conjugate(local))


# World changes up to WORLD_FULL radians are filtered in world axes, from there less and less, and
# beyond WORLD_NONE joint by joint (a part of a half turn flips its way round as it crosses 180
# degrees: rust/decouple.rs).
WORLD_FULL = np.pi / 3
WORLD_NONE = 2 * np.pi / 3


def world_trust(angle):
    """The share of a limb's world filter for world changes of ``angle``: 1 up to WORLD_FULL, 0
    from WORLD_NONE, a smoothstep between."""
    x = np.clip((WORLD_NONE - angle) / (WORLD_NONE - WORLD_FULL), 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x)


def _world(rotations: np.ndarray, parents: list[int], joint: int) -> np.ndarray:
    """World rotations ``[F, 4]`` of ``joint``: the local ``rotations [F, J, 4]`` from the root down."""
    chain = [joint]
    while parents[chain[-1]] >= 0:
        chain.append(parents[chain[-1]])
    turn = rotations[:, chain[-1]]
    for j in reversed(chain[:-1]):
        turn = quat.mul(turn, rotations[:, j])
    return turn


def _check_arms(parents: list[int], limbs: list[int], n_joints: int) -> None:
    ordered = len(parents) == n_joints and parents[0] == -1 and all(0 <= p < j for j, p in enumerate(parents) if j > 0)
    if not ordered:
        raise ArgumentError(
            f"argument `arm_parents`: expected the {n_joints} joints' parents, the root's -1 first, "
            "each before its child"
        )
    outside = [j for j in limbs if not 0 < j < n_joints]
    if outside:
        raise ArgumentError(
            f"argument `arm_joints`: joint {outside[0]} is not one of the {n_joints} joints below the root"
        )


def _check_trunk(joints: list[int], bones: np.ndarray, scale: float, n_joints: int) -> None:
    if not joints:
        return
    outside = [j for j in joints if not 0 <= j < n_joints]
    if outside:
        raise ArgumentError(f"argument `trunk_joints`: joint {outside[0]} is not one of the {n_joints} joints")
    if len(bones) != len(joints) or not np.all(np.isfinite(bones)) or np.linalg.norm(bones.sum(0)) <= 1e-12:
        raise ArgumentError(
            f"argument `trunk_bones`: expected one finite bone per trunk joint ({len(joints)}), "
            f"not all of zero length, got {bones.tolist()}"
        )
    if not (np.isfinite(scale) and scale > 0):
        raise ArgumentError(f"argument `trunk_scale`: must be a positive number, got {scale}")


def trunk_lean(original: np.ndarray, body: np.ndarray, joints: list[int], bones: np.ndarray) -> np.ndarray:
    """Per frame, the angle between the trunk lines of ``original`` and ``body``: the ``bones
    [n, 3]`` the chain ``joints`` carries, each turned by the chain down to its joint, summed."""
    lines = []
    for rotations in (original, body):
        turn = np.broadcast_to(np.array([0.0, 0.0, 0.0, 1.0]), rotations.shape[:1] + (4,))
        line = np.zeros(rotations.shape[:1] + (3,))
        for j, bone in zip(joints, np.asarray(bones, dtype=np.float64).reshape(-1, 3)):
            turn = quat.mul(turn, rotations[:, j])
            line = line + quat.rotate(turn, np.broadcast_to(bone, line.shape))
        lines.append(line)
    o, b = lines
    return np.arctan2(np.linalg.norm(np.cross(o, b), axis=-1), np.sum(o * b, axis=-1))


def compose_rotations(expressive: np.ndarray, body: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body``."""
    _check("expressive", body, expressive)
    if not np.isfinite(scale):
        raise ArgumentError(f"argument `scale`: must be a finite number, got {scale}")
    return quat.mul(expressive if scale == 1.0 else quat.power(expressive, scale), body)


def split_rotations_many(
    originals: list,
    bodies: list,
    gain: float,
    exponent: float,
    scale: np.ndarray,
    body_sigmas: list,
    activity_sigmas: list,
    trunk_joints=(),
    trunk_bones=(),
    trunk_scale: float = 1.0,
    arm_parents=(),
    arm_joints=(),
) -> list:
    """:func:`split_rotations` of each clip, in order (each with its own smoothing widths)."""
    chains = (trunk_joints, trunk_bones, trunk_scale, arm_parents, arm_joints)
    return [
        split_rotations(o, b, gain, exponent, scale, bs, a_s, *chains)
        for o, b, bs, a_s in zip(originals, bodies, body_sigmas, activity_sigmas, strict=True)
    ]


__all__ = [
    "compose_rotations",
    "decouple_rotations",
    "hang_limbs",
    "split_rotations",
    "split_rotations_many",
    "trunk_lean",
]
