"""Validation: the paper's swap test (with random and best same-size sets), the
leave-one-person-out warp, and how much the people agree on the ranking."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import partial

import numpy as np

from ..errors import ArgumentError, ModelError
from ..ops import forward_kinematics
from ..rotations import quat
from .dofs import dofs_to_rotations
from .fitting import fit, mapped
from .model import ExaggerationModel
from .settings import VALIDATION
from .timing import PREDICTABLE, fit_timing, mapped_timing


def dof_positions(model: ExaggerationModel, dofs: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """World joint positions ``[N, J, 3]`` of DOF frames ``[N, D]`` (rotations relative to
    ``reference [J, 4]``, heading removed), the hips at ``(0, height DOF x actor height, 0)``:
    the pose and the hips' height, without the path on the floor."""
    J = len(model.joint_names)
    rotations = dofs_to_rotations(dofs[:, : 3 * J], reference, model.representation, model.orders)
    translations = np.broadcast_to(model.offsets, (len(dofs), J, 3)).copy()
    translations[:, 0] = 0.0
    translations[:, model.hips] = 0.0
    translations[:, model.hips, 1] = dofs[:, -1] * model.height
    return forward_kinematics(rotations, translations, model.parents)[1]


@dataclass
class SwapResult:
    """The paper's test for one person (or the union): ``||swap - heavy|| / ||light - heavy||``
    over DOF trajectories and over world joint positions, for the key set (``swapped`` DOFs,
    ``share`` of all), a random set of the same size (mean of ``draws``) and the best set of that
    size (the DOFs with the largest light-heavy difference)."""

    person: str
    swapped: int
    share: float
    ratio: float
    ratio_positions: float
    random: float
    random_positions: float
    best: float
    best_positions: float


def _ratios(
    model: ExaggerationModel, light: np.ndarray, heavy: np.ndarray, reference: np.ndarray, sets: Sequence[np.ndarray]
) -> np.ndarray:
    """``[len(sets), 2]``: DOF and position ratios after swapping each set of DOFs light -> heavy."""
    hp = dof_positions(model, heavy, reference)
    base = np.linalg.norm(light - heavy), np.linalg.norm(dof_positions(model, light, reference) - hp)
    out = []
    for dofs in sets:
        swap = light.copy()
        swap[:, dofs] = heavy[:, dofs]
        out.append(
            (
                np.linalg.norm(swap - heavy) / base[0],
                np.linalg.norm(dof_positions(model, swap, reference) - hp) / base[1],
            )
        )
    return np.array(out)


def _swap_run(
    model: ExaggerationModel, label: str, pairs: list[int], key: np.ndarray, draws: int, rng: np.random.Generator
) -> SwapResult:
    """The swap test of ``key`` on each person of ``pairs`` (lightest against heaviest), averaged."""
    D = model.trajectories.shape[-1]
    n = int(key.sum())
    numbers = []
    for p in pairs:
        light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
        difference = np.linalg.norm(light - heavy, axis=0)
        sets = [np.flatnonzero(key), np.argsort(-difference)[:n]] + [
            rng.choice(D, n, replace=False) for _ in range(draws)
        ]
        numbers.append(_ratios(model, light, heavy, model.person_reference[p], sets))
    r = np.mean(numbers, axis=0)
    return SwapResult(
        label, n, n / D, r[0, 0], r[0, 1], float(r[2:, 0].mean()), float(r[2:, 1].mean()), r[1, 0], r[1, 1]
    )


def swap_test(
    model: ExaggerationModel,
    person: int | None = None,
    *,
    draws: int = VALIDATION.draws,
    seed: int = VALIDATION.seed,
    union_key: np.ndarray | None = None,
) -> list[SwapResult]:
    """Swap the key DOF trajectories of each person's lightest performance for the heaviest's
    and compare with the real heaviest (the paper's own validation). ``person``: one index, or every
    person (their own key sets) followed by ``"union"`` (every person with the union key set
    ``union_key``, by default :attr:`ExaggerationModel.key`; the people's ratios averaged)."""
    P, K, T, D = model.trajectories.shape
    rng = np.random.default_rng(seed)
    people = range(P) if person is None else [int(person)]
    results = []
    for p in people:
        if not 0 <= p < P:
            raise ArgumentError(f"person {p}: the model has {P} people")
        results.append(_swap_run(model, str(p), [p], model.person_key[p], draws, rng))
    if person is None and P > 1:
        key = model.key if union_key is None else np.asarray(union_key, dtype=bool)
        if key.shape != (D,):
            raise ArgumentError(f"argument `union_key`: expected {D} booleans, got shape {list(key.shape)}")
        results.append(_swap_run(model, "union", list(range(P)), key, draws, rng))
    return results


@dataclass
class RankAgreement:
    """Spearman rank correlation of the people's expressiveness ``E`` over the ``dofs`` DOFs that
    have ``E > 0`` for at least one person (DOFs that are 0 for everyone, such as zero-length joints,
    would only add ties): mean and lowest over every pair of people, and the same over all DOFs."""

    dofs: int
    mean: float
    lowest: float
    mean_all: float

    def text(self) -> str:
        return (
            f"rank agreement between people (Spearman, every pair): mean {self.mean:.3f} "
            f"(lowest {self.lowest:.3f}) over the "
            f"{self.dofs} DOFs with E > 0 for someone; {self.mean_all:.3f} over all DOFs"
        )


def rank_agreement(model: ExaggerationModel) -> RankAgreement:
    """How much the people agree on the ranking (needs at least two people)."""
    from scipy.stats import spearmanr

    E = model.expressiveness
    P = len(E)
    if P < 2:
        raise ModelError("rank agreement needs at least two people")
    live = (E > 0).any(axis=0)
    pairs = [(a, b) for a in range(P) for b in range(a + 1, P)]
    ranked = [float(spearmanr(E[a, live], E[b, live])[0]) for a, b in pairs]
    everything = [float(spearmanr(E[a], E[b])[0]) for a, b in pairs]
    return RankAgreement(int(live.sum()), float(np.mean(ranked)), float(np.min(ranked)), float(np.mean(everything)))


@dataclass
class WarpResult:
    """Leave-one-person-out: mappings (and basis, key set) from the other people, applied to this
    person's lightest performance towards the heaviest; ratios as in :class:`SwapResult`."""

    person: str
    key: int
    ratio: float
    ratio_positions: float


def leave_one_out(model: ExaggerationModel) -> list[WarpResult]:
    """For each person: fit on the others (same settings), warp the person's lightest cycle to
    the heaviest intensity (``x + U (f(k_K) - f(k_1))`` on the key DOFs) and compare with the real
    heaviest. Needs at least two people."""
    P = model.trajectories.shape[0]
    if P < 2:
        raise ModelError("leave-one-person-out needs at least two people")
    results = []
    for p in range(P):
        _, key, warped = _warped_by_the_others(model, p)
        light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
        reference = model.person_reference[p]
        hp = dof_positions(model, heavy, reference)
        ratio = np.linalg.norm(warped - heavy) / np.linalg.norm(light - heavy)
        light_distance = np.linalg.norm(dof_positions(model, light, reference) - hp)
        positions = np.linalg.norm(dof_positions(model, warped, reference) - hp) / light_distance
        results.append(WarpResult(str(p), int(key.sum()), float(ratio), float(positions)))
    return results


def _warped_by_the_others(model: ExaggerationModel, p: int) -> tuple[list[int], np.ndarray, np.ndarray]:
    """Person ``p``'s lightest performance warped to the heaviest intensity (``x + U (f(k_K) -
    f(k_1))`` on the key DOFs) by a fit of the other people with the model's settings: ``(the
    others, the fit's key DOFs [D], the warped performance [T, D])``."""
    others = [q for q in range(model.trajectories.shape[0]) if q != p]
    settings = model.training
    fitted = fit(
        model.trajectories[others], model.levels, model.weights, cycles=model.cycles_of(others),
        share=settings.share, energy=settings.energy, rank=settings.rank, degree=settings.degree,
    )  # fmt: skip
    low, high = model.levels[0], model.levels[-1]
    change = (mapped(fitted.mappings, high) - mapped(fitted.mappings, low)) * fitted.key[:, None]
    return others, fitted.key, model.trajectories[p, 0] + fitted.basis @ change.T


def timed_positions(
    model: ExaggerationModel, dofs: np.ndarray, reference: np.ndarray, timing: np.ndarray, seconds: float, fps: float
) -> np.ndarray:
    """World joint positions ``[N, J, 3]`` of a cycle ``dofs [T, D]`` played over ``seconds`` at
    ``fps`` with its timing features ``timing [2]`` (log duration in seconds, log travel in actor
    heights): the pose at each frame's phase, repeated cycle after cycle, the hips travelling
    along +Z (the heading is removed) as far a cycle as the travel says."""
    time = np.arange(int(round(seconds * fps))) / fps
    duration, travel = np.exp(timing[0]), np.exp(timing[1]) * model.height
    phase = (time / duration) % 1.0 * (len(dofs) - 1)
    positions = dof_positions(model, quat.resample(dofs, phase, rotations=False), reference)
    positions[..., 2] += (travel * time / duration)[:, None]
    return positions


@dataclass
class TimedResult:
    """The swap test and the leave-one-person-out warp over world joint positions in time
    (:func:`timed_positions`, two seconds), ``||x - heavy|| / ||light - heavy||``, with the
    light performance's timing kept (``*_without``) and with the timing swapped / warped too
    (``*_with``)."""

    person: str
    swap_without: float
    swap_with: float
    warp_without: float
    warp_with: float


def timing_validation(model: ExaggerationModel, seconds: float = 2.0, fps: float = 30.0) -> list[TimedResult]:
    """Each person's key DOFs swapped lightest -> heaviest, and warped with the mappings of the
    other people (as :func:`leave_one_out`), each compared with the real heaviest over world
    joint positions in time, without and with the timing features (swapped: the heaviest's;
    warped: the other people's timing mappings, for the features that follow the intensity);
    then the mean over people. Needs a model with timing and at least two people."""
    if not model.has_timing or model.cycle_timing is None:
        raise ModelError("the model holds no timing features (trained before them): train it again")
    P = model.trajectories.shape[0]
    if P < 2:
        raise ModelError("the timing validation needs at least two people")
    timing = fit_timing(model.cycle_timing, model.cycle_performance, model.levels).performances
    rows = []
    for p in range(P):
        others, _, warped = _warped_by_the_others(model, p)
        chosen = np.isin(model.cycle_performance[:, 0], others)
        owners = model.cycle_performance[chosen].copy()
        owners[:, 0] = np.searchsorted(others, owners[:, 0])
        theirs = fit_timing(model.cycle_timing[chosen], owners, model.levels)
        low, high = model.levels[0], model.levels[-1]
        timing_change = (
            mapped_timing(theirs.mappings, model.levels, high) - mapped_timing(theirs.mappings, model.levels, low)
        ) * (theirs.predictability >= PREDICTABLE)
        light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
        swap = light.copy()
        swap[:, model.person_key[p]] = heavy[:, model.person_key[p]]
        play = partial(timed_positions, model, reference=model.person_reference[p], seconds=seconds, fps=fps)
        target = play(heavy, timing=timing[p, -1])
        base = np.linalg.norm(play(light, timing=timing[p, 0]) - target)
        ratios = [
            np.linalg.norm(play(x, timing=t) - target) / base
            for x, t in (
                (swap, timing[p, 0]),
                (swap, timing[p, -1]),
                (warped, timing[p, 0]),
                (warped, timing[p, 0] + timing_change),
            )
        ]
        rows.append(TimedResult(str(p), *(float(r) for r in ratios)))
    mean = np.mean([[r.swap_without, r.swap_with, r.warp_without, r.warp_with] for r in rows], axis=0)
    return rows + [TimedResult("mean", *(float(v) for v in mean))]


def timing_table(results: Sequence[TimedResult]) -> str:
    """:func:`timing_validation`'s results as text."""
    lines = [f"{'person':<8} {'swap':>8} {'+timing':>8} | {'warp':>8} {'+timing':>8}"]
    for r in results:
        lines.append(
            f"{r.person:<8} {r.swap_without:8.3f} {r.swap_with:8.3f} | {r.warp_without:8.3f} {r.warp_with:8.3f}"
        )
    return "\n".join(lines)


def validation_table(
    swaps: Sequence[SwapResult], warps: Sequence[WarpResult] = (), agreement: RankAgreement | None = None
) -> str:
    """Both tests (and the people's rank agreement) as text."""
    lines = [
        f"{'person':<8} {'swapped':>11} {'ratio':>7} {'random':>7} {'best':>7} | {'pos.':>6} {'random':>7} {'best':>7}"
    ]
    for r in swaps:
        lines.append(
            f"{r.person:<8} {r.swapped:4d} ({r.share:4.0%}) {r.ratio:7.3f} {r.random:7.3f} {r.best:7.3f} | "
            f"{r.ratio_positions:6.3f} {r.random_positions:7.3f} {r.best_positions:7.3f}"
        )
    if warps:
        lines.append("")
        lines.append("leave-one-person-out warp, lightest -> heaviest (mappings from the other people):")
        lines.append(f"{'person':<8} {'key':>4} {'ratio':>7} {'pos.':>7}")
        for w in warps:
            lines.append(f"{w.person:<8} {w.key:4d} {w.ratio:7.3f} {w.ratio_positions:7.3f}")
        ratio, positions = np.mean([w.ratio for w in warps]), np.mean([w.ratio_positions for w in warps])
        lines.append(f"{'mean':<8} {'':>4} {ratio:7.3f} {positions:7.3f}")
    if agreement is not None:
        lines.append("")
        lines.append(agreement.text())
    return "\n".join(lines)


__all__ = [
    "RankAgreement",
    "SwapResult",
    "TimedResult",
    "WarpResult",
    "dof_positions",
    "leave_one_out",
    "rank_agreement",
    "swap_test",
    "timed_positions",
    "timing_table",
    "timing_validation",
    "validation_table",
]
