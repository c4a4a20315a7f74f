"""Joint positions (a motion-generation model's or a pose estimator's array) fitted as a motion,
then carried onto a chosen skeleton (:func:`fit_positions`).

- **The layout's own skeleton and rotations** (:mod:`.layout_fit`), read from the positions with
  the functions retargeting reads twists with, so the two agree.
- **Noise** (:mod:`.denoise`): noisy positions are smoothed over time first, the feet more
  through their contacts, and the fitted ankles put there by leg IK.
- Then :func:`~.retargeting.retarget_rigs` carries the motion onto the target (stance feet
  planted through the contacts it reads); clavicles the positions do not give turn towards their
  shoulders (:mod:`.clavicles`); given the target's own motion, its hips, limbs and stance feet
  sit as that motion holds them (:mod:`.habits`); feet the positions do not orient keep their
  toes out of the floor (:func:`~.planting.toes_above`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..body.jointmap import find_joint_map
from ..body.take import Take
from ..errors import MocapError
from ..motion import Motion, Skeleton
from .clavicles import reach_shoulders
from .denoise import DENOISE, noisy, steadied_fit
from .habits import habits, standing_as, with_habits
from .layout_fit import draft, fit_layout, full_map, own_names
from .layouts import Layout, layout_of, read_positions, upright
from .rig import _axis


class FitReport(NamedTuple):
    """How closely the result follows the positions: per role the target joint mapped to it,
    its mean and worst distance over the frames from the given position (carried onto the target
    as its hips' path is: the target's axes, scaled by the ratio of the legs' lengths; the
    constant lift that stands the feet on the target's floor taken out), in the target's units,
    and the same over all roles: the mean, and the worst frame's mean. ``metres_per_unit``: the
    target's unit; ``fps``, ``up``: the rate and up axis the positions were read with;
    ``denoised``: the Gaussian (frames at 30 fps) the positions were smoothed over (0: none);
    ``bones``: per bone of the spine and limbs both have, the mean angle (degrees) between its
    direction and the positions': what a fit onto another body is judged by, where the distances
    are mostly the two bodies' proportions."""

    roles: dict[str, str]
    mean: dict[str, float]
    worst: dict[str, float]
    mean_all: float
    worst_frame: float
    metres_per_unit: float
    fps: float
    up: str
    denoised: float = 0.0
    bones: dict[str, float] | None = None  # "role-role": mean degrees between the bone's directions


# The bones whose directions the report compares: the spine's and the limbs' (a foot's bone to its
# toes is carried by its flat stance, not its direction: not among them).
_REPORTED_BONES = [("hips", "chest"), ("chest", "head")] + [
    (f"{side}_{a}", f"{side}_{b}")
    for side in ("left", "right")
    for a, b in (
        ("clavicle", "upper_arm"),
        ("upper_arm", "forearm"),
        ("forearm", "hand"),
        ("upper_leg", "lower_leg"),
        ("lower_leg", "foot"),
    )
]


def fit_positions(
    positions,
    layout: Layout | str | None,
    target: Motion | Skeleton,
    *,
    fps: float | None = None,
    up: str | None = None,
    unit: str | None = None,
    sample: int = 0,
    plant_feet: bool = True,
    target_map: dict | None = None,
    smooth: float = 1.0,
    denoise: float | None = None,
) -> tuple[Motion, FitReport]:
    """Joint positions fitted as a motion on ``target``'s skeleton (a :class:`Motion`, whose frames
    tell its up axis and floor, or a bare :class:`Skeleton`), and how closely it follows them.

    ``positions``: an array (``[F, J, 3]``, ``[N, J, 3, F]``, ``[F, J*3]``) or an ``.npy``/``.npz``
    file (:func:`~.layouts.read_positions`); ``layout``: ``humanml3d``, ``smpl24``, ``h36m17``, a
    JSON layout file or a :class:`~.layouts.Layout` (None: the ``joints`` and ``parents`` an
    ``.npz`` carries); ``fps``: the positions' frame rate (default: the file's, else the layout's,
    else 30); ``up``: their up axis (``y`` or ``z``; default read from the data); ``unit``:
    their length unit (``m``, ``cm``...; default guessed from the legs); ``sample``: which of
    ``N``; ``plant_feet``, ``target_map``: as for :func:`~.retargeting.retarget`; ``smooth``: see
    :func:`~.layout_fit.fit_layout`; ``denoise``: a Gaussian (frames at 30 fps) the positions are smoothed over
    first (None: :data:`DENOISE` where :func:`noise` finds them noisy, else none)."""
    from .layouts import as_frames
    from .retargeting import retarget_rigs, rigs_for
    from .transfer import carried

    given = layout_of(layout) if isinstance(layout, str) else layout
    if isinstance(positions, np.ndarray):
        if given is None:
            raise MocapError("a layout is needed for an array of positions")
        points, file_fps = as_frames(positions, len(given.names), "positions", sample), None
    else:
        points, carried_layout, file_fps = read_positions(positions, given, sample)
        given = given or carried_layout
        if given is None:
            raise MocapError(f"{positions}: give a layout (the file carries no joints and parents)")
    fps = float(fps or file_fps or given.fps or 30.0)
    draft_map = find_joint_map(draft(points, given), given.joint_map)
    points, up_name = upright(points, draft_map, up)
    if denoise is None:
        denoise = DENOISE if noisy(points, draft_map, fps) else 0.0
    raw = points
    if denoise > 0:
        from scipy.ndimage import gaussian_filter1d  # here: SciPy takes a tenth of a second to import

        points = gaussian_filter1d(points, denoise * fps / 30.0, axis=0, mode="nearest")
    user_map = full_map(find_joint_map(draft(points, given), given.joint_map), own_names(given))
    if denoise > 0:  # noisy: the feet steadied through their contacts, then the fit
        motion, points = steadied_fit(points, raw, given, user_map, fps, smooth)
    else:
        motion = fit_layout(points, given, fps, smooth=smooth)
    from ..body.conventions import read_conventions

    conventions = None
    if unit is not None:
        from ..body.body import Body

        conventions = read_conventions(motion, Body.of(motion.skeleton, user_map).joint_map).with_overrides(unit=unit)
    # The target's motion, if any, read once: its stance (for the rig) and its habits.
    habitual = Take.of(target) if isinstance(target, Motion) and target.n_frames > 1 else None
    source, goal = rigs_for(motion, target if habitual is None else habitual, user_map, target_map, conventions)
    out = retarget_rigs(motion, source, goal, plant_feet=plant_feet)
    if habitual is not None:
        out = standing_as(out, goal, habitual, plant_feet)
    roles = [r for r in source.jmap.joints if r in goal.jmap.joints]
    placed = out.positions()[:, [goal.jmap[r] for r in roles]]
    wanted = carried(points[:, [source.jmap[r] for r in roles]], source, goal)
    hips = roles.index("hips")
    wanted = wanted + np.median(placed[:, hips] - wanted[:, hips], axis=0)  # the lift onto the floor
    if "left_clavicle" not in source.jmap.joints and "left_upper_arm" in roles:  # no clavicles given
        arms = [roles.index(f"{side}_upper_arm") for side in ("left", "right")]
        own = target.rotations if isinstance(target, Motion) else None  # the target's motion, if any
        out = reach_shoulders(out, goal.jmap, wanted[:, arms], own)
        placed = out.positions()[:, [goal.jmap[r] for r in roles]]
    if habitual is not None:
        out = with_habits(out, goal, habits(habitual, goal))
    if "left_toes" not in source.jmap.joints:  # the positions do not orient the feet: no toes into the floor
        from .planting import toes_above

        vertical = np.array(_axis(goal.conventions.up), float)
        out = toes_above(out, goal.jmap, vertical, goal.floor if goal.stance is None else goal.stance)
    report = _report(placed, wanted, roles, goal, fps, up_name, float(denoise))
    return out, report


def _report(
    placed: np.ndarray, wanted: np.ndarray, roles: list[str], goal, fps: float, up: str, denoised: float
) -> FitReport:
    """The :class:`FitReport` of the target's joints ``placed [F, R, 3]`` (of ``roles``) against
    the positions ``wanted`` there (carried onto the target, stood on its floor)."""
    distance = np.linalg.norm(placed - wanted, axis=-1)  # [F, R]
    bones = {}
    for a, b in _REPORTED_BONES:
        if a in roles and b in roles:
            ours, theirs = (p[:, roles.index(b)] - p[:, roles.index(a)] for p in (placed, wanted))
            lengths = np.linalg.norm(ours, axis=-1) * np.linalg.norm(theirs, axis=-1)
            cosine = np.sum(ours * theirs, axis=-1) / np.maximum(lengths, 1e-12)
            bones[f"{a}-{b}"] = float(np.degrees(np.arccos(np.clip(cosine, -1.0, 1.0))).mean())
    names = goal.skeleton.names
    return FitReport(
        {r: names[goal.jmap[r]] for r in roles},
        {r: float(d) for r, d in zip(roles, distance.mean(axis=0))},
        {r: float(d) for r, d in zip(roles, distance.max(axis=0))},
        float(distance.mean()),
        float(distance.mean(axis=1).max()),
        goal.conventions.metres_per_unit,
        fps,
        up,
        denoised,
        bones,
    )


__all__ = ["FitReport", "fit_positions"]
