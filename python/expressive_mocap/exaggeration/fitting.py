"""The method on DOF trajectories (steps 3-5): SVD basis, observability, predictability,
expressiveness ``E = O P^2``, key sets and the intensity-to-coefficient mappings. Returns a
:class:`FitResult`."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .settings import TRAINING


@dataclass(frozen=True)
class FitResult:
    """What :func:`fit` finds: ``basis [T, r]`` and its ``singular_values [r]``, the ``energy``
    share of ``sum(s^2)`` kept; ``expressiveness [P, D]`` (each person's ``E``, normalised) and
    ``overall [D]`` (their mean); ``key [D]`` (the union of the people's key sets ``person_key
    [P, D]``); ``mappings [D, r, degree + 1]`` (polynomials in k, highest power first, averaged
    over people)."""

    basis: np.ndarray
    singular_values: np.ndarray
    energy: float
    expressiveness: np.ndarray
    overall: np.ndarray
    key: np.ndarray
    person_key: np.ndarray
    mappings: np.ndarray


def mapped(mappings: np.ndarray, k, levels=None) -> np.ndarray:
    """``f(k) [..., D, r]``: polynomial mappings ``[D, r, degree + 1]`` (highest power first) at
    ``k``. Given the trained ``levels``, a curved mapping is continued beyond them along its
    tangent at the nearer end: a parabola through three styles would otherwise turn back (a walk
    taken below its lightest style, past the parabola's vertex, came out livelier)."""
    k = np.asarray(k, dtype=np.float64)
    out = _polynomial(mappings, k)
    if levels is None or mappings.shape[-1] < 3:  # lines go on as they are
        return out
    slopes = derivative(mappings)
    for end, beyond in ((float(np.min(levels)), k < np.min(levels)), (float(np.max(levels)), k > np.max(levels))):
        if np.any(beyond):
            tangent = _polynomial(mappings, end) + _polynomial(slopes, end) * (k - end)[..., None, None]
            out = np.where(beyond[..., None, None], tangent, out)
    return out


def derivative(mappings: np.ndarray) -> np.ndarray:
    """The mappings' derivatives ``[..., degree]`` (highest power first) of polynomial mappings
    ``[..., degree + 1]``."""
    degree = mappings.shape[-1] - 1
    return mappings[..., :-1] * np.arange(degree, 0, -1)


def _polynomial(mappings: np.ndarray, k) -> np.ndarray:
    k = np.asarray(k, dtype=np.float64)
    return np.einsum("dip,...p->...di", mappings, k[..., None] ** np.arange(mappings.shape[-1] - 1, -1, -1))


def _key_set(values: np.ndarray, share: float) -> np.ndarray:
    """The most expressive DOFs whose normalised values first reach ``share`` (bool ``[D]``)."""
    order = np.argsort(-values)
    reached = np.searchsorted(np.cumsum(values[order]), share - 1e-12) + 1
    key = np.zeros(len(values), dtype=bool)
    key[order[: min(reached, len(values))]] = True
    return key & (values > 0)


def _correlation(c: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Pearson correlation of ``c [K, ...]`` with ``k [K]`` along the first axis (0 where ``c`` is constant)."""
    dc = c - c.mean(axis=0)
    dk = (k - k.mean()).reshape((-1,) + (1,) * (c.ndim - 1))
    denominator = np.sqrt((dc * dc).sum(axis=0) * (dk * dk).sum())
    scale = 1e-12 * max(1.0, float(np.abs(c).max(initial=0.0)))
    return np.where(denominator > scale, (dc * dk).sum(axis=0) / np.where(denominator > 0, denominator, 1.0), 0.0)


def _single_cycles(trajectories: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each performance of ``trajectories [P, K, T, D]`` as its only cycle: ``(cycles [P K, T, D],
    performance [P K, 2])``."""
    P, K, T, D = trajectories.shape
    return trajectories.reshape(P * K, T, D), np.stack(np.unravel_index(np.arange(P * K), (P, K)), axis=1)


def _cycle_correlation(
    basis: np.ndarray, cycles: tuple[np.ndarray, np.ndarray], levels: np.ndarray, people: int
) -> np.ndarray:
    """``rho [P, D, r]``: per person, the correlation of every cycle's coefficients with its intensity."""
    coefficients = np.einsum("tr,ntd->ndr", basis, cycles[0])
    person, level = cycles[1].T
    return np.stack([_correlation(coefficients[person == p], levels[level[person == p]]) for p in range(people)])


def fit(
    trajectories: np.ndarray,
    levels: np.ndarray,
    weights: np.ndarray,
    *,
    cycles: tuple[np.ndarray, np.ndarray] | None = None,
    share: float = TRAINING.share,
    energy: float = TRAINING.energy,
    rank: int | None = TRAINING.rank,
    degree: int = TRAINING.degree,
) -> FitResult:
    """The method on DOF trajectories ``[P, K, T, D]`` at intensities ``levels [K]`` with DOF
    weights ``[D]``: basis, expressiveness, key sets, mappings. ``cycles``: every cycle the
    performances were averaged from, ``(trajectories [N, T, D], performance [N, 2])`` (person and
    intensity index of each), over which predictability is measured; by default each performance
    is its only cycle."""
    P, K, T, D = trajectories.shape
    levels = np.asarray(levels, dtype=np.float64)
    A = trajectories.transpose(2, 0, 1, 3).reshape(T, P * K * D)  # intensity after intensity, person after person
    U, s, _ = np.linalg.svd(A, full_matrices=False)
    total = float(np.sum(s * s))
    if rank is None:
        rank = int(np.searchsorted(np.cumsum(s * s) / max(total, 1e-300), energy - 1e-12) + 1)
    rank = int(min(max(rank, 1), len(s)))
    U, s = U[:, :rank], s[:rank]
    C = np.einsum("tr,pktd->pkdr", U, trajectories)  # coefficients [P, K, D, r]
    observability = np.linalg.norm(C[:, 0] - C[:, -1], axis=-1) * weights  # [P, D]
    rho = _cycle_correlation(U, _single_cycles(trajectories) if cycles is None else cycles, levels, P)  # [P, D, r]
    predictability = np.abs(rho) @ (s / s.sum())
    E = observability * predictability**2
    sums = E.sum(axis=1, keepdims=True)
    E = np.where(sums > 0, E / np.where(sums > 0, sums, 1.0), 0.0)
    person_key = np.stack([_key_set(e, share) for e in E])
    # Mappings: a polynomial per person, DOF and basis vector; coefficients averaged over people.
    V = np.vander(levels, degree + 1)  # [K, degree + 1]
    per_person = np.linalg.lstsq(V, C.transpose(1, 0, 2, 3).reshape(K, -1), rcond=None)[0]  # [degree + 1, P D r]
    mappings = per_person.reshape(degree + 1, P, D, rank).mean(axis=1).transpose(1, 2, 0)
    return FitResult(
        basis=U,
        singular_values=s,
        energy=float(np.sum(s * s) / max(total, 1e-300)),
        expressiveness=E,
        overall=E.mean(axis=0),
        key=person_key.any(axis=0),
        person_key=person_key,
        mappings=mappings,
    )


__all__ = ["FitResult", "fit", "mapped"]
