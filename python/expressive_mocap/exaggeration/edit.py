"""Exaggerating or diminishing a motion (step 7): ``x' = x + U (f(k1) - f(k0))`` on the key DOFs
of every cycle, in its own timing, cross-faded at cycle boundaries, clamped to the training range
plus a margin, the stance feet locked; :class:`ExaggerationReport` says what was done."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..body.contacts import foot_contacts
from ..body.hinges import HingeReport, limit_hinges
from ..body.take import Take
from ..errors import ArgumentError, ModelError
from ..motion import Motion
from ..rotations import quat
from ..rotations.quat import mean_rotation
from .cycles import Cycle, SampledCycles, cycles_for, frame_yaw, sample_cycles, to_cycle_timing, without_heading
from .dofs import dofs_to_rotations, rotations_to_dofs, sampled_dofs
from .estimate import POOR_FIT, IntensityEstimate
from .footlock import IDENTITY, lock_stance_feet
from .model import ExaggerationModel
from .settings import EDITING, EditSettings, Reference
from .timing import (
    PREDICTABLE,
    Timing,
    cycle_timing,
    held_still,
    mapped_timing,
    retime,
    time_warp,
    timing_factors,
)


@dataclass
class ExaggerationReport:
    """What :func:`exaggerate` did: intensities (``k0`` estimated or given), cycles edited, DOFs clamped
    (``{dof: (frames, largest excess)}``), the largest rotation change per joint (degrees), foot
    locking's largest ankle correction, the largest distance it could not close and how far it
    lowered the hips (file units), stance-foot speeds before and after; ``estimate`` how ``k0`` was
    estimated (None when given); ``baseline`` the baseline clip's given intensity and the one it
    is estimated at without its own offsets removed (None without a baseline); ``timing`` how the
    cycles were retimed (None when the timing was left as it was)."""

    k0: float
    k1: float
    k0_estimated: bool
    cycles: list[Cycle]
    clamped: dict[str, tuple[int, float]]
    largest_change: dict[str, float]
    foot_correction: float
    foot_residual: float
    hips_lowered: float
    stance_speed_input: float
    stance_speed_output: float
    estimate: IntensityEstimate | None = None
    baseline: tuple[float, float] | None = None
    timing: Timing | None = None
    hinges: HingeReport | None = None

    def text(self) -> str:
        e = self.estimate
        k0 = f"{self.k0:.3g} +- {e.uncertainty:.2g} (estimated)" if e is not None else f"{self.k0:.3g}"
        lines = [
            f"intensity {k0} -> {self.k1:.3g}; {len(self.cycles)} cycle(s) edited"
            + (f" (frames {self.cycles[0].start}-{self.cycles[-1].end})" if self.cycles else ""),
        ]
        if e is not None:
            lines.append(
                f"estimate: fit residual {e.residual:.2f} (the training performances' own: about 1); "
                f"uncertainty from the key joints "
                f"{e.jackknife:.2g}, the cycles {e.bootstrap:.2g}, the training clips' own error {e.training:.2g}"
                + (f" (x {min(e.residual, POOR_FIT):.2g} for the fit residual)" if e.residual > 1 else "")
            )
            if e.warning():
                lines.append("warning: " + e.warning())
        if self.baseline is not None:
            lines.append(
                f"baseline: given intensity {self.baseline[0]:g}, estimated at {self.baseline[1]:.3g}; "
                "its offsets from the model removed before estimating and clamping"
            )
        if self.clamped:
            worst = sorted(self.clamped.items(), key=lambda kv: -kv[1][1])
            lines.append(
                f"clamped to the training range (+margin), {len(worst)} DOF(s): "
                + ", ".join(f"{d} ({n} frames, by up to {_amount(d, v)})" for d, (n, v) in worst[:8])
            )
        else:
            lines.append("nothing clamped")
        lines.append(self.timing.text() if self.timing is not None else "timing: unchanged")
        if self.hinges is not None:
            lines.append(self.hinges.text())
        changes = sorted(self.largest_change.items(), key=lambda kv: -kv[1])
        lines.append(
            "largest change per joint (degrees): " + ", ".join(f"{n} {v:.1f}" for n, v in changes if v >= 0.05)[:600]
            or "largest change: none"
        )
        lines.append(
            f"stance-foot speed {self.stance_speed_input:.3g} -> {self.stance_speed_output:.3g} (file units/s); "
            f"foot locking moved the ankles by up to {self.foot_correction:.3g} "
            f"(out of reach by up to {self.foot_residual:.3g}), lowering the hips "
            f"by up to {self.hips_lowered:.3g} where a leg could not reach"
        )
        return "\n".join(lines)


def _amount(dof: str, value: float) -> str:
    return f"{value:.3f} x height" if dof.endswith(".height") else f"{np.degrees(value):.1f} deg"


def stance_foot_speed(motion: Motion | Take, contacts: np.ndarray) -> float:
    """Mean horizontal speed (file units per second) of the feet (ankle and toe) over the frames
    where ``contacts [F, 2]`` says they touch the floor."""
    take = Take.of(motion)
    motion, roles, p = take.motion, take.body.roles, take.positions
    speeds = []
    for s in (0, 1):
        for joint in (roles.feet[s], roles.toes[s]):
            v = np.linalg.norm(np.diff(p[:, joint, [0, 2]], axis=0), axis=-1) / motion.frame_time
            both = contacts[1:, s] & contacts[:-1, s]
            speeds.append(v[both])
    every = np.concatenate(speeds)
    return float(every.mean()) if len(every) else 0.0


def _per_frame_change(delta: np.ndarray, cycles: Sequence[Cycle], n_frames: int, fade: int) -> np.ndarray:
    """The normalised change ``delta [T, D]`` laid on every cycle's own frames ``-> [F, D]`` (0
    outside the cycles), each jump at a cycle boundary split half and half over ``fade`` frames
    either side with a raised cosine, so no seam appears at the footstrikes."""
    out = np.zeros((n_frames, delta.shape[1]))
    for c in cycles:
        out[c.start : c.end + 1] = to_cycle_timing(delta, c.n_frames)
    if fade < 1 or not cycles:
        return out
    # Boundaries: between frame a (left) and a + 1 (right). Cycle c owns frames start .. end - 1
    # (its end is the next cycle's start); the last owns its end frame too.
    lefts = [cycles[0].start - 1] + [c.end - 1 for c in cycles[:-1]] + [cycles[-1].end]
    if len(cycles) > 1:
        for c, nxt in zip(cycles[:-1], cycles[1:]):
            out[c.end] = to_cycle_timing(delta, nxt.n_frames)[0]
    g = 0.5 * (1 + np.cos(np.pi * np.arange(fade) / fade))  # 1 at the boundary, -> 0
    corrected = out.copy()
    for a in lefts:
        if a < 0 or a + 1 >= n_frames:
            continue  # nothing beyond the clip's edge to fade into
        jump = out[a + 1] - out[a]
        for i in range(fade):
            if a - i >= 0:
                corrected[a - i] += 0.5 * jump * g[i]
            if a + 1 + i < n_frames:
                corrected[a + 1 + i] -= 0.5 * jump * g[i]
    return corrected


def motion_dofs(model: ExaggerationModel, motion: Motion | Take, yaw: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """DOFs ``[F, D]`` of every frame of ``motion`` (heading ``yaw [F]`` removed, rotations relative to
    ``reference``; the hips height in units of the motion's own actor height, as in training, so a
    model trained in centimetres edits a motion in metres)."""
    take = Take.of(motion)
    motion, roles = take.motion, take.body.roles
    rot = rotations_to_dofs(
        without_heading(motion.rotations, roles.hips, yaw), reference, model.representation, model.orders
    )
    heights = take.positions[:, roles.hips, 1] / take.body.actor_height
    return np.concatenate([rot, heights[:, None]], axis=1)


def _check_arguments(
    model: ExaggerationModel,
    motion: Motion,
    to: float,
    current: float | None,
    baseline: Motion | None,
    level: float | None,
) -> None:
    """Refuse what :func:`exaggerate` cannot work with (its settings are checked by
    :class:`EditSettings` itself), naming the argument."""
    if not isinstance(motion, Motion):
        raise ArgumentError(f"argument `motion`: expected a Motion, got {type(motion).__name__}")
    model.check_skeleton(motion)
    for name, value in (("to", to), ("current", current)):
        if value is not None and not _finite_number(value):
            raise ArgumentError(f"argument `{name}`: intensities must be finite numbers, got {value!r}")
    if (baseline is None) != (level is None):
        raise ArgumentError("baseline and baseline_level go together: a clip of the same actor and its known intensity")
    if baseline is not None:
        if not isinstance(baseline, Motion) or baseline.n_frames < 3:
            raise ArgumentError(f"argument `baseline`: expected a Motion of at least 3 frames, got {baseline!r}")
        try:
            model.check_skeleton(baseline)
        except ModelError as error:
            raise ModelError(f"baseline: {error}") from None
        if not _finite_number(level):
            raise ArgumentError(f"argument `baseline_level`: baseline_level must be a finite number, got {level!r}")
    if motion.n_frames < 3:
        raise ArgumentError(f"a motion of {motion.n_frames} frames is too short to exaggerate")


def _finite_number(value: object) -> bool:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        return False
    return bool(np.isfinite(value))


def _clamp(
    model: ExaggerationModel, X: np.ndarray, target: np.ndarray, reference: str, margin: float, shift: np.ndarray
) -> tuple[np.ndarray, dict[str, tuple[int, float]]]:
    """``target [F, D]`` kept within the training range moved by ``shift [D]`` (in the same
    parameterisation as ``X``, the input's DOFs), widened by the margin and never tighter than the
    input itself; with what was clamped (``{dof: (frames, largest excess)}``)."""
    lower, upper = model.dof_range(reference)
    lower, upper = lower + shift, upper + shift
    width = upper - lower
    low = np.minimum(lower - margin * width, X)
    high = np.maximum(upper + margin * width, X)
    clamped_values = np.clip(target, low, high)
    excess = np.abs(clamped_values - target)
    clamped = {
        model.dof_names[d]: (int(np.count_nonzero(excess[:, d] > 1e-12)), float(excess[:, d].max()))
        for d in np.flatnonzero(excess.max(axis=0) > 1e-12)
    }
    return clamped_values, clamped


def _rebuilt(
    model: ExaggerationModel,
    take: Take,
    X: np.ndarray,
    new: np.ndarray,
    ref: np.ndarray,
    yaw: np.ndarray,
) -> Motion:
    """``motion`` with the joints whose DOFs changed from ``X`` to ``new [F, D]`` rotated anew (the
    heading ``yaw`` put back) and the hips raised by the height DOF's change."""
    motion, roles = take.motion, take.body.roles
    J = motion.skeleton.n_joints
    changed = np.flatnonzero(np.abs(new - X).max(axis=0) > 0)
    rotations = motion.rotations.copy()
    translations = motion.translations.copy()
    joints = sorted({int(d) // 3 for d in changed if d < 3 * J})
    if joints:
        rebuilt = dofs_to_rotations(new[:, : 3 * J], ref, model.representation, model.orders)
        rebuilt[:, roles.hips] = quat.mul(quat.about("Y", yaw), rebuilt[:, roles.hips])  # the heading back
        rotations[:, joints] = rebuilt[:, joints]
    world_rotations = take.fk[0]
    parent = motion.skeleton.parents[roles.hips]
    parent_rot = world_rotations[:, parent] if parent >= 0 else np.broadcast_to(IDENTITY, (motion.n_frames, 4))
    lift = np.zeros((motion.n_frames, 3))
    lift[:, 1] = (new[:, -1] - X[:, -1]) * take.body.actor_height  # the motion's units, not the model's
    translations[:, roles.hips] += quat.rotate(quat.conjugate(parent_rot), lift)
    return Motion(motion.skeleton, rotations, translations, motion.frame_time)


@dataclass
class _Retimed:
    """An edit at its new timing: the input retimed alike (what the edit is compared with), the
    contacts at the new frames, the ankles held still through them (None: the input's) and what
    was done (None: nothing)."""

    motion: Motion
    edited: Motion
    contacts: np.ndarray
    ankles: np.ndarray | None = None
    timing: Timing | None = None


def _retimed(
    model: ExaggerationModel,
    take: Take,
    edited: Motion,
    cycles: Sequence[Cycle],
    contacts: np.ndarray,
    levels: tuple[float, float],
    margin: float,
) -> _Retimed:
    """``edited`` with its cycles' duration and the hips' travel over them multiplied by what the
    timing mappings give from ``levels`` (k0, k1), for the features that follow the intensity;
    unchanged when the model has no timing or nothing changes."""
    motion, roles = take.motion, take.body.roles
    same = _Retimed(motion, edited, contacts)
    if not model.has_timing or not cycles:
        return same
    assert model.timing_mappings is not None and model.timing_predictability is not None
    live = model.timing_predictability >= PREDICTABLE
    to, k0 = (mapped_timing(model.timing_mappings, model.levels, k) for k in (levels[1], levels[0]))
    change = (to - k0) * live
    own = cycle_timing(take, cycles)
    # The training range is in actor heights; the motion's own travel is measured the same way.
    factors, clamped = timing_factors(change, own.mean(axis=0), *model.timing_range(), margin)
    if np.abs(factors - 1).max() < 1e-9:
        return same
    span = (cycles[0].start, cycles[-1].end)
    warp = time_warp(motion.n_frames, cycles, float(factors[0]))
    out, _ = retime(edited, roles, warp, span, float(factors[1]))
    seconds, travel = np.exp(own).mean(axis=0) * [1.0, take.body.actor_height]
    timing = Timing(
        float(factors[0]), float(factors[1]), clamped, (seconds, travel),
        (seconds * factors[0], travel * factors[1]), warp, span,
    )  # fmt: skip
    held, new_contacts, ankles = held_still(motion, contacts, roles, timing)
    return _Retimed(held, out, new_contacts, ankles, timing)


def _own_reference(motion: Motion, hips: int, cycles: Sequence[Cycle], yaw: np.ndarray) -> np.ndarray:
    """The motion's own mean rotations ``[J, 4]`` (heading removed) over its cycles' frames."""
    heading_free = without_heading(motion.rotations, hips, yaw)
    return mean_rotation(heading_free[cycles[0].start : cycles[-1].end + 1])


def _coefficients(model: ExaggerationModel, sampled: SampledCycles, reference: np.ndarray) -> np.ndarray:
    """Coefficients ``[C, D, r]`` of each sampled cycle's DOFs, rotations measured from ``reference``."""
    return np.einsum("tr,ctd->cdr", model.basis, sampled_dofs(sampled, reference, model.representation, model.orders))


@dataclass
class _Measured:
    """A motion measured for editing: its cycles, each frame's heading ``yaw [F]``, the rotations'
    ``reference [J, 4]``, each cycle's coefficients ``[C, D, r]`` measured from it, and those the
    current intensity is estimated from (``estimated``: from the motion's own mean rotations, so
    a joint held otherwise throughout changes none of them, unless the estimate is to read offsets)."""

    cycles: list[Cycle]
    yaw: np.ndarray
    reference: np.ndarray
    coefficients: np.ndarray
    estimated: np.ndarray


def _measure(
    model: ExaggerationModel,
    take: Take,
    edit: EditSettings,
    cycles: Sequence[Cycle] | None = None,
) -> _Measured:
    motion = take.motion
    if cycles is None:
        cycles = cycles_for(take, model.settings.cycle, model.settings.foot)
    cycles = list(cycles)
    yaw = frame_yaw(take, cycles)
    own = _own_reference(motion, take.body.roles.hips, cycles, yaw)
    ref = model.reference if edit.reference == "model" else own
    sampled = sample_cycles(take, cycles, model.basis.shape[0])
    coefficients = _coefficients(model, sampled, ref)
    same = edit.estimate_offsets or edit.reference == "own"
    return _Measured(cycles, yaw, ref, coefficients, coefficients if same else _coefficients(model, sampled, own))


def _baseline_offsets(
    model: ExaggerationModel, baseline: Motion, level: float, edit: EditSettings
) -> tuple[np.ndarray, np.ndarray, float]:
    """What the actor of ``baseline`` (at intensity ``level``) does otherwise than the model at that
    level: the difference of the coefficients the estimate reads ``[D, r]``, and of each DOF's mean
    ``[D]`` as the edit measures it (the shift of the training range); with the intensity the
    baseline is estimated at as it is."""
    measured = _measure(model, Take.of(baseline), edit)
    at_level = model.predict_coefficients(level)
    as_is = model.estimate(measured.estimated.mean(axis=0), offsets=edit.estimate_offsets).k
    shift = (model.basis @ (measured.coefficients.mean(axis=0) - at_level).T).mean(axis=0)
    return measured.estimated.mean(axis=0) - at_level, shift, as_is


def current_intensity(
    model: ExaggerationModel, motion: Motion | Take, cycles: Sequence[Cycle] | None = None
) -> IntensityEstimate:
    """``motion``'s current intensity as :func:`exaggerate` estimates it by default (its
    ``cycles``, else its gait cycles or the whole clip): with the fit residual that tells how much
    the motion is like the model's training performances (about 1 alike, above
    :data:`~expressive_mocap.exaggeration.estimate.POOR_FIT` unlike)."""
    measured = _measure(model, Take.of(motion), EDITING, cycles)
    return model.estimate(measured.estimated.mean(axis=0), measured.estimated)


# Over 60 lines with its docstring, which documents every option; the body is about 45.
def exaggerate(
    model: ExaggerationModel,
    motion: Motion,
    to: float,
    *,
    current: float | None = None,
    cycles: Sequence[Cycle] | None = None,
    reference: Reference = EDITING.reference,
    margin: float = EDITING.margin,
    fade: float = EDITING.fade,
    lock_feet: bool = EDITING.lock_feet,
    blend: float = EDITING.blend,
    baseline: Motion | None = None,
    baseline_level: float | None = None,
    estimate_offsets: bool = EDITING.estimate_offsets,
    timing: bool = EDITING.timing,
    hinges: bool = EDITING.hinges,
    settings: EditSettings | None = None,
) -> tuple[Motion, ExaggerationReport]:
    """Exaggerate (``to`` above the current intensity) or diminish ``motion`` with ``model``.

    ``current`` is ``k0``; by default (None) it is estimated from the mean coefficients of the
    motion's cycles by least squares over the key DOFs' mapped coefficients, each weighted by how
    well the mapping predicts it (:meth:`ExaggerationModel.estimate`), from how each DOF varies
    over the cycle only, so an actor's own posture (a joint held otherwise throughout) does not
    move it (``estimate_offsets`` True: from the DOFs' means too); the report holds the estimate
    with its uncertainty and fit residual, and a ``UserWarning`` says when it is outside the
    trained range. ``baseline`` (a clip of the same actor and action at the known intensity
    ``baseline_level``): its coefficients' difference from the model's at that level is removed
    from the motion's before estimating, and the training range the DOFs are clamped to is moved
    by it. Every cycle (``cycles``: default, the footstrike-to-footstrike cycles of the foot the
    model was trained with; a single whole-clip cycle when none is found) gets
    ``x' = x + U (f(to) - f(k0))`` on the key DOFs, in its own timing; frames outside the cycles
    keep their values and the changes are cross-faded over ``fade`` seconds at every boundary.
    DOFs are kept within the training range widened by ``margin`` x its width (never pushed past
    where they already were). ``reference`` "model" measures rotations from the training people's
    mean pose, "own" from the motion's own mean. The DOF range is the one seen in training,
    measured from the same reference (see :meth:`ExaggerationModel.dof_range`). ``lock_feet`` pins
    each stance foot (ankle position and foot orientation) to the input's during its contacts
    with two-bone leg IK, blended in and out over ``blend`` seconds, so the edit adds no skating
    (see :func:`lock_stance_feet`). ``timing``: the cycles' duration and the hips' travel over them
    change too, by the model's timing mappings (:mod:`~expressive_mocap.exaggeration.timing`),
    kept within the training range (+ margin); the output then has another number of frames,
    and foot locking holds each stance foot still through its contacts at the new timing.
    ``hinges``: elbows and knees kept from straight to the most the training cycles bend them
    plus a margin, never tighter than the input has them, before the edit is retimed and the feet
    are locked (:func:`~expressive_mocap.body.hinges.limit_hinges`; the report's ``hinges``).
    Defaults: :data:`~expressive_mocap.exaggeration.EDITING`; ``settings``: all of them at once,
    an :class:`~expressive_mocap.exaggeration.EditSettings` (the keywords then left as they are).
    A bad value is an :class:`~expressive_mocap.errors.ArgumentError` naming its argument.
    Returns the new motion and an :class:`ExaggerationReport`.
    """
    _check_arguments(model, motion, to, current, baseline, baseline_level)
    keywords = EditSettings(reference, margin, fade, lock_feet, blend, estimate_offsets, timing, hinges)
    edit = _one_of(settings, keywords)
    take = Take.of(motion)
    roles = take.body.roles
    contacts = foot_contacts(take)
    measured = _measure(model, take, edit, cycles)
    cycles, yaw, ref = measured.cycles, measured.yaw, measured.reference
    X = motion_dofs(model, take, yaw, ref)  # [F, D]
    offset, shift, read_as = np.zeros_like(measured.coefficients[0]), np.zeros(model.n_dofs), None
    if baseline is not None and baseline_level is not None:
        offset, shift, as_is = _baseline_offsets(model, baseline, float(baseline_level), edit)
        read_as = (float(baseline_level), as_is)
    per_cycle = measured.estimated - offset
    estimate = (
        None
        if current is not None
        else model.estimate(per_cycle.mean(axis=0), per_cycle, offsets=edit.estimate_offsets)
    )
    k0 = estimate.k if estimate is not None else float(current)  # type: ignore[arg-type]
    if estimate is not None and estimate.warning():
        warnings.warn(estimate.warning(), stacklevel=2)
    change = (model.predict_coefficients(float(to)) - model.predict_coefficients(k0)) * model.key[:, None]  # [D, r]
    per_frame = _per_frame_change(model.basis @ change.T, cycles, motion.n_frames, int(round(edit.fade * motion.fps)))
    new, clamped = _clamp(model, X, X + per_frame, edit.reference, edit.margin, shift)
    out = _rebuilt(model, take, X, new, ref, yaw)
    limited = None
    if edit.hinges:  # before the feet are locked, so that the leg IK bends each knee the right way
        out, limited = limit_hinges(out, model.hinge_limits, allow=(motion.rotations,))
    at = _retimed(model, take, out, cycles, contacts, (k0, float(to)), edit.margin) if edit.timing else None
    held, out, held_contacts = (at.motion, at.edited, at.contacts) if at else (motion, out, contacts)
    correction = residual = lowered = 0.0
    if edit.lock_feet and (np.abs(new - X).max(initial=0.0) > 0 or (at and at.timing)):
        out, correction, residual, lowered = lock_stance_feet(
            held, out, held_contacts, roles, int(round(edit.blend * motion.fps)), at.ankles if at else None
        )
    angles = np.degrees(quat.angle(quat.mul(quat.conjugate(held.rotations), out.rotations))).max(axis=0)
    report = ExaggerationReport(
        k0=k0, k1=float(to), k0_estimated=estimate is not None, cycles=cycles, clamped=clamped, estimate=estimate,
        largest_change={n: float(a) for n, a in zip(motion.skeleton.names, angles)},
        foot_correction=correction, foot_residual=residual, hips_lowered=lowered,
        stance_speed_input=stance_foot_speed(take, contacts),
        stance_speed_output=stance_foot_speed(out, held_contacts), baseline=read_as,
        timing=at.timing if at else None, hinges=limited,
    )  # fmt: skip
    return out, report


def _one_of(settings: EditSettings | None, keywords: EditSettings) -> EditSettings:
    """The edit's settings: ``settings`` when given (the keywords then left at their defaults, or
    the same), else the keywords'."""
    if settings is None:
        return keywords
    if not isinstance(settings, EditSettings):
        raise ArgumentError(f"argument `settings`: expected an EditSettings, got {type(settings).__name__}")
    if keywords not in (EDITING, settings):
        raise ArgumentError("argument `settings`: give the edit's settings as `settings` or as keywords, not both")
    return settings


__all__ = ["ExaggerationReport", "current_intensity", "exaggerate", "motion_dofs", "stance_foot_speed"]
