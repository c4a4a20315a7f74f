"""A motion's current intensity (step 6): weighted least squares over the key DOFs' mapped
coefficients, with an uncertainty (key joints left out, cycles resampled, the training
performances' own error) and a fit residual: :class:`IntensityEstimate`."""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .fitting import derivative, mapped

if TYPE_CHECKING:
    from .model import ExaggerationModel

BOOTSTRAP_DRAWS = 200
POOR_FIT = 2.0  # estimate residual above which the motion is reported as unlike the training performances


@dataclass(frozen=True)
class IntensityEstimate:
    """A motion's estimated current intensity ``k``. ``uncertainty`` (one standard deviation, in
    intensity units) combines how much the key joints disagree (``jackknife``: leave one joint's
    DOFs out), how much the motion's own cycles do (``bootstrap``: resampled) and how far the
    training performances come out from their own intensities (``training``: RMS; counted times
    the residual when that is between 1 and :data:`POOR_FIT`: on walks of another capture session,
    residuals 1.6-3.0, the errors were 1.6 times the uncertainty without). ``residual``:
    the weighted misfit at ``k`` relative to the training performances' own (about 1 for a
    performance like the training ones; well above 1, the motion is not much like them).
    ``trained``: the lowest and highest trained intensity."""

    k: float
    uncertainty: float
    residual: float
    jackknife: float
    bootstrap: float
    training: float
    trained: tuple[float, float]

    @property
    def outside(self) -> bool:
        """Outside the trained range by more than twice the uncertainty."""
        low, high = self.trained
        return self.k + 2 * self.uncertainty < low or self.k - 2 * self.uncertainty > high

    @property
    def poor_fit(self) -> bool:
        """The residual is above :data:`POOR_FIT` (a model of dataset-2's walks: its own walks
        0.67-1.22, runs 2.6-4.6, a wave 6.2, another session's forward and sideways walks 1.4-3.1;
        reading the DOFs' means too, its own walks 0.55-1.12, each take left out of training
        0.59-1.19, a turning walk 1.75, runs 2.4-3.5, a wave 5.8)."""
        return self.residual > POOR_FIT

    def warning(self) -> str:
        """What is wrong with the estimate ("" when nothing)."""
        low, high = self.trained
        problems = []
        if self.outside:
            problems.append(
                f"the estimated current intensity {self.k:.3g} +- {self.uncertainty:.2g} is outside the trained range "
                f"{low:g}-{high:g} (the mappings extrapolate there)"
            )
        if self.poor_fit:
            problems.append(
                f"the motion fits the model poorly (residual {self.residual:.2f}; the training performances' about 1): "
                "is it the same action?"
            )
        return "; ".join(problems) + ("; give the current intensity if known" if problems else "")


def weighted_intensity(mappings: np.ndarray, weights: np.ndarray, c: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """Weighted least-squares intensities ``[B]`` of coefficients ``c [B, n, r]`` under polynomial
    ``mappings [n, r, degree + 1]`` (highest power first; a curved one continued along its tangents
    beyond ``levels``, as :func:`~expressive_mocap.exaggeration.fitting.mapped` continues it) with
    ``weights [n, r]``: closed form for lines; otherwise the exact minimum over the trained range
    widened by twice its span, among the real roots of the error's derivative within the levels,
    the closed form on each tangent and the range's ends."""
    degree = mappings.shape[-1] - 1
    if degree == 0:
        return np.full(len(c), float(np.mean(levels)))
    if degree == 1:
        return _on_line(mappings, weights, c, levels)
    first, last = float(levels[0]), float(levels[-1])
    span = last - first
    low, high = first - 2 * span, last + 2 * span
    slopes = derivative(mappings)
    tangents = [  # each end's tangent as a line [n, r, 2]: slope, intercept
        np.stack([mapped(slopes, end), mapped(mappings, end) - mapped(slopes, end) * end], axis=-1)
        for end in (first, last)
    ]
    candidates = np.concatenate(
        [
            _stationary(mappings, weights, c, first, last),
            np.clip(_on_line(tangents[0], weights, c, levels), low, first)[:, None],
            np.clip(_on_line(tangents[1], weights, c, levels), last, high)[:, None],
            np.tile([low, high], (len(c), 1)),
        ],
        axis=1,
    )
    errors = np.einsum("nr,bknr->bk", weights, (mapped(mappings, candidates, levels) - c[:, None]) ** 2)
    return candidates[np.arange(len(c)), np.argmin(errors, axis=1)]


def _on_line(lines: np.ndarray, weights: np.ndarray, c: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """The weighted least-squares intensities ``[B]`` under straight mappings ``lines [n, r, 2]``
    (the levels' mean where they are flat)."""
    slope, intercept = lines[..., 0], lines[..., 1]
    denominator = float(np.sum(weights * slope * slope))
    if denominator <= 0:
        return np.full(len(c), float(np.mean(levels)))
    return np.sum(weights * slope * (c - intercept), axis=(1, 2)) / denominator


def _stationary(mappings: np.ndarray, weights: np.ndarray, c: np.ndarray, low: float, high: float) -> np.ndarray:
    """Where the weighted error ``sum w (f(k) - c)^2`` of the polynomial is flat, per row of ``c [B, n, r]``:
    ``[B, 2 degree - 1]`` real roots of ``sum w (f(k) - c) f'(k)`` (clipped to ``low``-``high``;
    a complex root stands in as its clipped real part: one more point tried, never a wrong one)."""
    degree = mappings.shape[-1] - 1
    gap = np.broadcast_to(mappings, c.shape + (degree + 1,)).copy()
    gap[..., -1] -= c
    slopes = derivative(mappings)
    product = np.zeros((len(c), 2 * degree))  # highest power first
    for i in range(degree + 1):
        for j in range(degree):
            product[:, i + j] += np.einsum("nr,bnr,nr->b", weights, gap[..., i], slopes[..., j])
    lead = product[:, :1]
    safe = np.abs(lead) > 1e-12 * np.abs(product).max(axis=1, keepdims=True)
    monic = product[:, 1:] / np.where(safe, lead, 1.0)
    size = 2 * degree - 1
    companion = np.zeros((len(c), size, size))
    companion[:, 0, :] = -monic
    companion[:, np.arange(1, size), np.arange(size - 1)] = 1.0
    roots = np.linalg.eigvals(companion).real
    return np.clip(np.where(safe, roots, low), low, high)


def _jackknife(key: np.ndarray, mappings: np.ndarray, weights: np.ndarray, c: np.ndarray, levels: np.ndarray) -> float:
    """The spread of the intensity with one key joint's DOFs left out at a time (they move together)."""
    joints = np.flatnonzero(key) // 3
    groups = [joints == j for j in np.unique(joints)]
    if len(groups) <= 1:
        return 0.0
    left_out = np.array([weighted_intensity(mappings, weights * ~g[:, None], c[None], levels)[0] for g in groups])
    n = len(groups)
    return float(np.sqrt((n - 1) / n * np.sum((left_out - left_out.mean()) ** 2)))


def _bootstrap(cycles: np.ndarray | None, mappings: np.ndarray, weights: np.ndarray, levels: np.ndarray) -> float:
    """The spread of the intensity over resampled cycles ``[C, n, r]`` (0 with fewer than two)."""
    if cycles is None or len(cycles) <= 1:
        return 0.0
    draws = np.random.default_rng(0).integers(0, len(cycles), size=(BOOTSTRAP_DRAWS, len(cycles)))
    return float(np.std(weighted_intensity(mappings, weights, cycles[draws].mean(axis=1), levels)))


def offset_projection(basis: np.ndarray) -> np.ndarray:
    """``[r, r]``: removes from coefficients ``[..., r]`` (as ``c @ P``) the direction a constant
    trajectory has in the basis ``[T, r]`` (``U^T 1``), so a constant added to a DOF trajectory
    (an actor's own posture: a joint held a few degrees otherwise throughout) leaves them unchanged;
    what is left is how the trajectory varies over the cycle."""
    u = basis.sum(axis=0)
    norm = float(u @ u)
    return np.eye(len(u)) - (np.outer(u, u) / norm if norm > 0 else 0.0)


def estimate_intensity(
    model: ExaggerationModel,
    coefficients: np.ndarray,
    cycle_coefficients: np.ndarray | None = None,
    *,
    offsets: bool = False,
) -> IntensityEstimate:
    """The current intensity of a motion from its coefficients ``[D, r]`` under ``model``; see
    :meth:`ExaggerationModel.estimate <expressive_mocap.exaggeration.ExaggerationModel.estimate>`.
    ``offsets`` False: from how each key DOF varies over the cycle only (:func:`offset_projection`
    applied to the motion's, the training performances' and the mapped coefficients alike)."""
    key, levels = model.key, model.levels
    project = np.eye(model.basis.shape[1]) if offsets else offset_projection(model.basis)
    mappings = np.einsum("ij,njp->nip", project, model.mappings[key])
    c = np.asarray(coefficients, dtype=np.float64)[key] @ project
    trained = np.einsum("tr,pktd->pkdr", model.basis, model.trajectories)[:, :, key] @ project  # [P, K, n, r]
    spread = ((trained - mapped(mappings, levels, levels)[None]) ** 2).mean(axis=(0, 1))
    # No coefficient counts as predicted better than to a tenth of the typical change over the
    # trained range: training data exactly on the lines (one noiseless person) would otherwise
    # weigh in without bound; with that floor alone the weights are equal (plain least squares).
    change = mapped(mappings, levels[-1]) - mapped(mappings, levels[0])
    floor = 0.01 * float(np.mean(change**2)) if change.size else 0.0
    weights = 1.0 / (spread + (floor if floor > 0 else 1.0))
    k = float(weighted_intensity(mappings, weights, c[None], levels)[0])
    jackknife = _jackknife(key, mappings, weights, c, levels)
    cycles = None if cycle_coefficients is None else np.asarray(cycle_coefficients, dtype=np.float64)[:, key] @ project
    bootstrap = _bootstrap(cycles, mappings, weights, levels)
    # ... and how far the training performances themselves come out from their intensities.
    P, K = trained.shape[:2]
    trained = trained.reshape(P * K, *trained.shape[2:])
    trained_k = weighted_intensity(mappings, weights, trained, levels)
    training = float(np.sqrt(np.mean((trained_k - np.tile(levels, P)) ** 2)))

    def misfit(c: np.ndarray, k: np.ndarray) -> np.ndarray:  # weighted RMS distance from the mapping at k
        return np.sqrt(np.einsum("nr,bnr->b", weights, (mapped(mappings, k, levels) - c) ** 2) / weights.sum())

    # The residual in units of the training performances' own (at least the floor's tenth of the change).
    typical = max(float(np.sqrt(np.mean(misfit(trained, trained_k) ** 2))), np.sqrt(floor))
    residual = float(misfit(c[None], np.array([k]))[0] / typical) if typical > 0 else 0.0
    # A motion that fits the mappings worse than the training performances do (another actor or
    # session) is estimated less surely: the training error grows with the residual, up to
    # POOR_FIT (beyond, the warning says the estimate is not to be trusted anyway).
    scaled = training * min(max(residual, 1.0), POOR_FIT)
    uncertainty = float(np.sqrt(jackknife**2 + bootstrap**2 + scaled**2))
    return IntensityEstimate(
        k, uncertainty, residual, jackknife, bootstrap, training, (float(levels[0]), float(levels[-1]))
    )


__all__ = [
    "BOOTSTRAP_DRAWS",
    "POOR_FIT",
    "IntensityEstimate",
    "estimate_intensity",
    "offset_projection",
    "weighted_intensity",
]
