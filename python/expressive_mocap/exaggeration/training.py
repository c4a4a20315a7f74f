"""Training (steps 1-5 on clips): each person's performances as DOF trajectories, then
:func:`~expressive_mocap.exaggeration.fit`, gathered into an :class:`ExaggerationModel`."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..body.body import Body
from ..body.roles import JointRoles
from ..body.take import Take
from ..errors import ArgumentError, ClipError, MocapError
from ..motion import Motion, Skeleton
from ..rotations.quat import mean_rotation
from .cycles import check_cycle_choice, choose_cycles, sample_cycles
from .dofs import dof_names, dof_weights, dofs_to_rotations, rotations_to_dofs, sampled_dofs, subtree_weights
from .fitting import fit
from .model import ExaggerationModel
from .settings import REPRESENTATIONS, TRAINING, CycleChoice, TrainSettings
from .timing import cycle_timing, fit_timing


@dataclass
class _PersonDofs:
    """One person's training DOFs: each performance's trajectory ``[K, T, D]`` (the mean of its
    cycles in DOF space), every cycle ``[N, T, D]`` with its performance's index ``[N]``, and the
    person's mean rotations ``[J, 4]`` (over every sample of every clip) they are measured from, and
    every cycle's timing features ``[N, 2]`` (:func:`~expressive_mocap.exaggeration.timing.cycle_timing`)."""

    performances: np.ndarray
    cycles: np.ndarray
    cycle_level: np.ndarray
    reference: np.ndarray
    timing: np.ndarray


def _person_dofs(motions: Sequence[Motion], settings: TrainSettings) -> _PersonDofs:
    sampled, timing = [], []
    for k, m in enumerate(motions):
        take = Take.of(m)
        try:
            cycles = choose_cycles(take, settings.cycle, settings.foot)
            sampled.append(sample_cycles(take, cycles, settings.samples))
            timing.append(cycle_timing(take, cycles))
        except MocapError as error:  # which clip: the caller knows the person, and maybe the file
            raise ClipError(str(error), -1, k) from None
    everything = np.concatenate([s.rotations.reshape(-1, *s.rotations.shape[2:]) for s in sampled])
    reference = mean_rotation(everything)
    orders = motions[0].skeleton.euler_orders
    per_clip = [sampled_dofs(s, reference, settings.representation, orders) for s in sampled]
    return _PersonDofs(
        performances=np.stack([c.mean(axis=0) for c in per_clip]),
        cycles=np.concatenate(per_clip),
        cycle_level=np.repeat(np.arange(len(per_clip)), [len(c) for c in per_clip]),
        reference=reference,
        timing=np.concatenate(timing),
    )


def _check_settings(settings: TrainSettings, K: int) -> None:
    if settings.representation not in REPRESENTATIONS:
        raise ArgumentError(
            f"representation must be one of {', '.join(REPRESENTATIONS)}, got {settings.representation!r}"
        )
    if not 0 < settings.share <= 1 or not 0 < settings.energy <= 1:
        raise ArgumentError(f"share and energy must be in (0, 1], got {settings.share} and {settings.energy}")
    if not 0 <= int(settings.degree) < K:
        raise ArgumentError(
            f"degree {settings.degree}: a polynomial mapping needs fewer degrees than intensities ({K})"
        )
    if int(settings.samples) < 3:
        raise ArgumentError(f"samples (T) must be at least 3, got {settings.samples}")
    if settings.foot not in (0, 1):
        raise ArgumentError(f"foot must be 0 (left) or 1 (right), got {settings.foot!r}")


def _check_levels(people: list[list[Motion]], levels: np.ndarray) -> None:
    K = len(levels)
    if K < 2 or not np.all(np.diff(levels) > 0) or not np.isfinite(levels).all():
        raise ArgumentError(f"intensities must be at least two increasing numbers, got {levels.tolist()}")
    if not people or any(len(p) != K for p in people):
        raise ArgumentError(f"each person needs one clip per intensity ({K}); got {[len(p) for p in people]}")


def _check_skeletons(people: list[list[Motion]]) -> Skeleton:
    for m in (m for p in people for m in p):
        if not isinstance(m, Motion):
            raise ArgumentError(f"expected Motion objects, got {type(m).__name__}")
    skeleton = people[0][0].skeleton
    for i, person in enumerate(people):
        for k, m in enumerate(person):
            if m.skeleton.names != skeleton.names:
                raise ClipError(
                    f"another skeleton ({m.skeleton.n_joints} joints, {', '.join(m.skeleton.names[:3])}, ...) than the "
                    f"first clip's ({skeleton.n_joints} joints, {', '.join(skeleton.names[:3])}, ...): "
                    "a model is trained on clips of one skeleton",
                    i,
                    k,
                )
    return skeleton


def _common_range(
    per_person: list[_PersonDofs], reference: np.ndarray, skeleton: Skeleton, representation: str
) -> np.ndarray:
    """Every training cycle's DOFs ``[N T, D]`` with the rotations measured from the people's mean
    ``reference`` (each person's are measured from their own mean, which may differ by degrees):
    the training range in the parameterisation a new motion is edited in."""
    orders = np.asarray(skeleton.euler_orders).astype(np.int64)
    J = skeleton.n_joints
    common = np.concatenate(
        [
            rotations_to_dofs(
                dofs_to_rotations(d.cycles[..., :-1].reshape(-1, 3 * J), d.reference, representation, orders),
                reference,
                representation,
                orders,
            )
            for d in per_person
        ]
    )
    heights = np.concatenate([d.cycles for d in per_person])[..., -1].reshape(-1, 1)
    return np.concatenate([common, heights], axis=1)


def train(
    people: Sequence[Sequence[Motion]],
    levels: Sequence[float],
    *,
    samples: int = TRAINING.samples,
    share: float = TRAINING.share,
    energy: float = TRAINING.energy,
    rank: int | None = TRAINING.rank,
    degree: int = TRAINING.degree,
    representation: str = TRAINING.representation,
    cycle: CycleChoice = TRAINING.cycle,
    foot: int = TRAINING.foot,
    joint_map: dict | None = None,
) -> ExaggerationModel:
    """Rank the expressive features of one action and fit the intensity mappings.

    ``people[p][k]`` is person ``p``'s performance at intensity ``levels[k]`` (one list per person;
    one person is ``[[light, medium, heavy]]``). ``cycle`` picks each clip's cycles (see
    :func:`~expressive_mocap.exaggeration.cycles.choose_cycles`): "all" by default (the performance
    is their mean; predictability is measured over every one), "middle" for the paper's single
    cycle, "whole" or ``(start, end)`` for actions that are not walks. ``samples`` is ``T``;
    ``energy`` the basis' share of ``sum(s^2)`` unless ``rank`` is given; ``share`` the
    expressiveness accumulated into the key set; ``degree`` the mappings' polynomial degree (<
    number of intensities); ``foot`` (0 = left, 1 = right) the foot whose footstrikes start a
    walking cycle, here and in :func:`~expressive_mocap.exaggeration.exaggerate` (the basis is
    phase-aligned to it). ``joint_map``: roles the clips' skeleton's names and topology do not
    tell (a map file's form); the model records the whole map, by which motions of other skeletons
    reach it. Defaults: :data:`~expressive_mocap.exaggeration.TRAINING`.
    """
    from ..body.conventions import upright

    # Cycles, headings and heights are read along Y: a Z-up skeleton's clips are turned upright
    # first, and the model is of the upright skeleton (exaggerate turns a Z-up motion likewise).
    clips = [[upright(m) for m in p] for p in people]
    intensities = np.asarray(levels, dtype=np.float64).reshape(-1)
    _check_levels(clips, intensities)
    settings = TrainSettings(samples, share, energy, rank, degree, representation, cycle, foot)
    _check_settings(settings, len(intensities))
    check_cycle_choice(cycle)
    settings = TrainSettings(int(samples), share, energy, rank, int(degree), representation, cycle, int(foot))
    skeleton = _check_skeletons(clips)
    roles = Body.of(skeleton).roles
    per_person = []
    for i, person in enumerate(clips):
        try:
            per_person.append(_person_dofs(person, settings))
        except ClipError as error:
            raise ClipError(str(error), i, error.level) from None
    model = _model(skeleton, roles, intensities, per_person, settings)
    model.joint_map = _recorded_map(skeleton, joint_map)
    return model


def _model(
    skeleton: Skeleton, roles: JointRoles, levels: np.ndarray, per_person: list[_PersonDofs], settings: TrainSettings
) -> ExaggerationModel:
    """Fit the people's DOFs and gather everything into the model."""
    X = np.stack([d.performances for d in per_person])
    refs = np.stack([d.reference for d in per_person])
    cycle_trajectories = np.concatenate([d.cycles for d in per_person])
    cycle_performance = np.concatenate(
        [np.stack([np.full(len(d.cycles), p), d.cycle_level], axis=1) for p, d in enumerate(per_person)]
    )
    weights = dof_weights(skeleton, roles, subtree_weights(skeleton))
    fitted = fit(
        X, levels, weights, cycles=(cycle_trajectories, cycle_performance), share=settings.share,
        energy=settings.energy, rank=settings.rank, degree=settings.degree,
    )  # fmt: skip
    timing = fit_timing(np.concatenate([d.timing for d in per_person]), cycle_performance, levels)
    reference = mean_rotation(refs)
    common = _common_range(per_person, reference, skeleton, settings.representation)
    return ExaggerationModel(
        joint_names=skeleton.names,
        parents=np.asarray(skeleton.parents),
        offsets=np.asarray(skeleton.offsets),
        height=Body.of(skeleton).actor_height,
        hips=roles.hips,
        orders=np.asarray(skeleton.euler_orders).astype(np.int64),
        representation=settings.representation,
        dof_names=tuple(dof_names(skeleton, settings.representation)),
        weights=weights,
        levels=levels,
        basis=fitted.basis,
        singular_values=fitted.singular_values,
        energy=fitted.energy,
        expressiveness=fitted.expressiveness,
        overall=fitted.overall,
        key=fitted.key,
        person_key=fitted.person_key,
        mappings=fitted.mappings,
        reference=reference,
        person_reference=refs,
        lower=common.min(axis=0),
        upper=common.max(axis=0),
        trajectories=X,
        cycle_trajectories=cycle_trajectories,
        cycle_performance=cycle_performance,
        settings=settings,
        cycle_timing=np.concatenate([d.timing for d in per_person]),
        timing_mappings=timing.mappings,
        timing_predictability=timing.predictability,
    )


def _recorded_map(skeleton, user_map: dict | None) -> dict:
    """The joint map a model records of its skeleton (``user_map``'s roles, the rest found by names
    and topology), by which motions of other skeletons reach it; {} when the skeleton has none
    and no map was given (the model then takes its own skeleton only)."""
    try:
        return Body.of(skeleton, user_map).joint_map.as_names()
    except MocapError:
        if user_map:
            raise
        return {}


__all__ = ["train"]
