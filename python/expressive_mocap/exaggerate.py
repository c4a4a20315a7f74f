"""Expressive features for movement exaggeration (Davis & Kannappan, "Expressive Features for
Movement Exaggeration", SIGGRAPH 2002 sketch).

From performances of one action at known intensities (e.g. walks 'exhausted' < 'normal' <
'active' as 1 < 2 < 3), find the joint-angle trajectories (DOFs) that change most and most
predictably with intensity (the *key features*), model their change, and exaggerate or diminish
a new motion of the same action.

Pipeline and shapes (``T`` samples a cycle, ``D`` DOFs, ``K`` intensities, ``P`` people,
``r`` basis vectors):

1. a cycle (footstrike to next footstrike of the same foot, or a whole clip) resampled to ``T``
   samples (slerp / linear) with the heading removed (the hips pre-multiplied by the inverse yaw
   of the cycle's travel direction);
2. DOFs ``[T, D]``: per joint the rotation vector of ``m_j^-1 q_j`` (``m_j`` the joint's mean over
   the person's samples, one hemisphere), 3 a joint, plus the hips height / actor height
   (``D = 3 J + 1``); Euler channels relative to the mean as an option;
3. ``A [T, P K D]``, thin SVD, ``U [T, r]`` keeping 99% of ``sum(s^2)``; coefficients ``U^T x``;
4. observability ``O_d = ||c_d(k_1) - c_d(k_K)|| w_j`` (``w_j`` the summed bone lengths below
   joint ``j``), predictability ``P_d = sum_i s_i / sum(s) |rho(c_{d,i}(k), k)|``,
   ``E_d = O_d P_d^2``, normalised and accumulated to ``share`` (0.9): key features.
   By default (``cycle="all"``) a performance is the mean of every cycle of its clip (in DOF
   space) and ``rho`` is taken over every cycle, each at its clip's intensity. With one sample
   per intensity (the paper's single cycle; ``cycle="middle"``) three points decide ``rho``, and for
   three points the correlation of pure noise follows the arcsine law (median ``|rho|`` 0.71), so
   a DOF that only varies scores almost as predictable as one that follows the intensity; over
   every cycle (about 20 a person on the Bandai walks) ``rho`` also sees the step-to-step spread;
5. least-squares lines ``c_{d,i}(k)``, averaged over people;
6. a new motion's current intensity ``k0`` (given, or estimated by least squares over the key
   DOFs' mapped coefficients weighted by how well the mapping predicts each, with an uncertainty
   and a fit residual: :meth:`ExaggerationModel.estimate`);
7. per cycle: ``x' = x + U (f(k1) - f(k0))`` on the key DOFs, mapped back onto each
   cycle's own frames, cross-faded at cycle boundaries, clamped to the training range plus a
   margin, optionally with the stance foot locked.
"""

from __future__ import annotations

import io
import json
import os
import warnings
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from . import quat
from .errors import ClipError, MocapError
from .features import foot_contacts, footstrikes
from .quat import mean_rotation
from .ik import two_bone_ik
from .files import atomic_write, check_keys, finite_array, read_model_file
from .ops import euler_to_quat, forward_kinematics, quat_to_euler
from .motion import Motion, Skeleton
from .roles import JointRoles, actor_height, facing_yaw

FORMAT = "expressive-mocap exaggeration model"
# 3: every training cycle kept (cycle_trajectories, cycle_performance); 2: lower / upper measured
# from the people's mean rotations (1: from each person's own)
VERSION = 3
REPRESENTATIONS = ("rotvec", "euler")
CYCLE_CHOICES = ("all", "middle", "first", "whole")
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])

# --------------------------------------------------------------------------- cycles


@dataclass(frozen=True)
class Cycle:
    """Frames ``start`` to ``end`` (both included; ``end`` is the next footstrike of ``foot``,
    0 = left, 1 = right, -1 for a whole clip or a given range)."""

    start: int
    end: int
    foot: int = -1

    @property
    def n_frames(self) -> int:
        return self.end - self.start + 1


def find_cycles(motion: Motion, roles: JointRoles | None = None, contacts: np.ndarray | None = None, foot: int | None = 0) -> list[Cycle]:
    """Gait cycles of a walk: footstrike to next footstrike of ``foot`` (0 = left, the default, so
    that every cycle of every clip starts in the same phase; None: the foot whose cycles cover
    more frames). The cycles follow each other without gaps; empty when the foot never strikes twice."""
    if contacts is None:
        contacts = foot_contacts(motion, roles)
    strikes = footstrikes(contacts)
    best: list[Cycle] = []
    for side in (0, 1) if foot is None else (int(foot),):
        frames = strikes[strikes[:, 1] == side, 0]
        cycles = [Cycle(int(a), int(b), side) for a, b in zip(frames[:-1], frames[1:]) if b - a >= 2]
        if sum(c.n_frames for c in cycles) > sum(c.n_frames for c in best):
            best = cycles
    return best


def normalise_cycle(motion: Motion, cycle: Cycle, samples: int = 50) -> Motion:
    """The frames of ``cycle`` resampled to ``samples`` frames over the same span (slerp for
    rotations, linear for translations): the time-normalised cycle."""
    if cycle.start < 0 or cycle.end >= motion.n_frames or cycle.end - cycle.start < 1:
        raise MocapError(f"cycle frames {cycle.start}-{cycle.end} do not fit a {motion.n_frames}-frame motion")
    return motion[cycle.start : cycle.end + 1].resample(n_frames=samples)


def to_cycle_timing(trajectory: np.ndarray, n_frames: int) -> np.ndarray:
    """Map a normalised trajectory ``[T, ...]`` back to a cycle of ``n_frames`` frames (the
    inverse of the uniform time normalisation: linear interpolation at each frame's phase)."""
    trajectory = np.asarray(trajectory, dtype=np.float64)
    samples = len(trajectory)
    position = np.linspace(0.0, samples - 1, n_frames)
    i0 = np.minimum(np.floor(position).astype(int), samples - 2)
    t = (position - i0).reshape((-1,) + (1,) * (trajectory.ndim - 1))
    return (1 - t) * trajectory[i0] + t * trajectory[i0 + 1]


# --------------------------------------------------------------------------- DOFs


def subtree_weights(skeleton: Skeleton) -> np.ndarray:
    """``w_j [J]``: the summed length of every bone below joint ``j`` (its children's offsets, their
    children's, ..., End Sites included): a shoulder moves the whole arm."""
    weights = np.zeros(skeleton.n_joints)
    for j, off in skeleton.end_sites:
        weights[j] += float(np.linalg.norm(off))
    for j in range(skeleton.n_joints - 1, 0, -1):  # children come after parents
        parent = skeleton.parents[j]
        weights[parent] += weights[j] + float(np.linalg.norm(skeleton.offsets[j]))
    return weights


def dof_names(skeleton: Skeleton, representation: str = "rotvec") -> list[str]:
    """Names of the ``3 J + 1`` DOFs: ``Joint.rx ry rz`` (rotation vector) or ``Joint.Zrot ...`` (Euler,
    in the joint's order), then ``Hips.height``."""
    names = []
    for j, joint in enumerate(skeleton.names):
        axes = "xyz" if representation == "rotvec" else skeleton.rotation_order(j)
        names += [f"{joint}.r{a}" if representation == "rotvec" else f"{joint}.{a}rot" for a in axes]
    return names + ["Hips.height"]


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def rotations_to_dofs(rotations: np.ndarray, reference: np.ndarray, representation: str, orders: np.ndarray) -> np.ndarray:
    """Local rotations ``[N, J, 4]`` (heading removed) -> rotation DOFs ``[N, 3 J]`` relative to the
    ``reference [J, 4]`` (rotation vector of ``ref^-1 q``, or Euler angles minus the reference's,
    wrapped to (-pi, pi], radians)."""
    if representation == "rotvec":
        return quat.log(quat.mul(quat.conjugate(reference)[None], rotations)).reshape(len(rotations), -1)
    angles = np.radians(quat_to_euler(rotations, orders)) - np.radians(quat_to_euler(reference[None], orders))
    return _wrap(angles).reshape(len(rotations), -1)


def dofs_to_rotations(dofs: np.ndarray, reference: np.ndarray, representation: str, orders: np.ndarray) -> np.ndarray:
    """The inverse of :func:`rotations_to_dofs`: ``[N, 3 J]`` -> ``[N, J, 4]``."""
    dofs = dofs.reshape(len(dofs), -1, 3)
    if representation == "rotvec":
        return quat.mul(reference[None], quat.exp(dofs))
    angles = np.degrees(dofs + np.radians(quat_to_euler(reference[None], orders)))
    return euler_to_quat(angles, orders)


def _yaw(vector: np.ndarray) -> float:
    """Degrees about Y that turn +Z towards the horizontal ``vector``."""
    return float(np.degrees(np.arctan2(vector[0], vector[2])))


def cycle_heading(motion: Motion, roles: JointRoles, cycle: Cycle, positions: np.ndarray | None = None) -> float:
    """The yaw (degrees) of a cycle's travel direction: the hips' horizontal displacement from its
    first to its last frame; where the hips barely travel (< 5% of the actor's height), the
    facing direction (perpendicular to the line from the right to the left upper leg)."""
    if positions is None:
        positions = motion.positions()
    hips = positions[[cycle.start, cycle.end], roles.hips]
    travel = hips[1] - hips[0]
    travel[1] = 0.0
    if np.linalg.norm(travel) >= 0.05 * actor_height(motion.skeleton, roles):
        return _yaw(travel)
    return facing_yaw(positions[cycle.start : cycle.end + 1], roles)


def _without_heading(rotations: np.ndarray, hips: int, yaw: np.ndarray) -> np.ndarray:
    """Rotations with the hips pre-multiplied by the inverse of ``yaw`` (degrees, per frame or one)."""
    out = rotations.copy()
    out[:, hips] = quat.mul(quat.about("Y", -np.broadcast_to(yaw, len(rotations))), rotations[:, hips])
    return out


@dataclass
class _Sampled:
    """Time-normalised cycles of one clip: heading-free rotations ``[C, T, J, 4]`` and hips
    heights / actor height ``[C, T]``."""

    rotations: np.ndarray
    heights: np.ndarray


def _sample_cycles(motion: Motion, roles: JointRoles, cycles: Sequence[Cycle], samples: int) -> _Sampled:
    positions = motion.positions()
    height = actor_height(motion.skeleton, roles)
    rots, heights = [], []
    for cycle in cycles:
        yaw = cycle_heading(motion, roles, cycle, positions)
        part = normalise_cycle(motion, cycle, samples)
        rots.append(_without_heading(part.rotations, roles.hips, yaw))
        heights.append(part.positions()[:, roles.hips, 1] / height)
    return _Sampled(np.stack(rots), np.stack(heights))


def _choose_cycles(motion: Motion, roles: JointRoles, cycle: str | int | tuple, foot: int = 0) -> list[Cycle]:
    """The cycles of a training clip for ``cycle`` = "all" (every one), "middle" (the one nearest the
    clip's middle: steady walking), "first", "whole" (the clip), an index, or a ``(start, end)``
    frame range; walking cycles run from one footstrike of ``foot`` to the next."""
    if isinstance(cycle, tuple):
        start, end = (int(v) for v in cycle)
        return [Cycle(start, end)]
    if cycle == "whole":
        return [Cycle(0, motion.n_frames - 1)]
    if cycle not in CYCLE_CHOICES and not isinstance(cycle, (int, np.integer)):
        raise MocapError(f"cycle must be one of {', '.join(CYCLE_CHOICES)}, an index or a (start, end) range, got {cycle!r}")
    cycles = find_cycles(motion, roles, foot=foot)
    if not cycles:
        raise MocapError(
            f"no gait cycle found in its {motion.n_frames} frames (no foot strikes twice): for an action other than "
            "walking take the whole clip (--cycle whole; in Python cycle='whole') or a (start, end) frame range"
        )
    if cycle == "first":
        return cycles[:1]
    if cycle == "all":
        return cycles
    if cycle == "middle":
        middle = motion.n_frames / 2
        return [min(cycles, key=lambda c: abs((c.start + c.end) / 2 - middle))]
    if isinstance(cycle, (int, np.integer)):
        if not -len(cycles) <= cycle < len(cycles):
            raise MocapError(f"cycle {cycle}: the clip has {len(cycles)} cycles")
        return [cycles[cycle]]
    raise MocapError(f"cycle must be one of {', '.join(CYCLE_CHOICES)}, an index or a (start, end) range, got {cycle!r}")


# --------------------------------------------------------------------------- intensity

BOOTSTRAP_DRAWS = 200
POOR_FIT = 2.0  # estimate residual above which the motion is reported as unlike the training performances


@dataclass(frozen=True)
class IntensityEstimate:
    """A motion's estimated current intensity ``k``. ``uncertainty`` (one standard deviation, in
    intensity units) combines how much the key joints disagree (``jackknife``: leave one joint's
    DOFs out), how much the motion's own cycles do (``bootstrap``: resampled) and how far the
    training performances come out from their own intensities (``training``: RMS). ``residual``:
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
        0.55-1.12, each take left out of training 0.59-1.19, a turning walk 1.75, runs 2.4-3.5,
        a wave 5.8)."""
        return self.residual > POOR_FIT

    def warning(self) -> str:
        """What is wrong with the estimate ("" when nothing)."""
        low, high = self.trained
        problems = []
        if self.outside:
            problems.append(f"the estimated current intensity {self.k:.3g} +- {self.uncertainty:.2g} is outside the trained range "
                            f"{low:g}-{high:g} (the mappings extrapolate there)")
        if self.poor_fit:
            problems.append(f"the motion fits the model poorly (residual {self.residual:.2f}; the training performances' about 1): is it the same action?")
        return "; ".join(problems) + ("; give the current intensity if known" if problems else "")


def _weighted_intensity(mappings: np.ndarray, weights: np.ndarray, c: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """Weighted least-squares intensities ``[B]`` of coefficients ``c [B, n, r]`` under polynomial
    ``mappings [n, r, degree + 1]`` with ``weights [n, r]``: closed form for lines; otherwise the
    best of a grid over the trained range widened by twice its span, refined by Gauss-Newton."""
    degree = mappings.shape[-1] - 1
    if degree == 0:
        return np.full(len(c), float(np.mean(levels)))
    if degree == 1:
        slope, intercept = mappings[..., 0], mappings[..., 1]
        denominator = float(np.sum(weights * slope * slope))
        if denominator <= 0:
            return np.full(len(c), float(np.mean(levels)))
        return np.sum(weights * slope * (c - intercept), axis=(1, 2)) / denominator
    span = float(levels[-1] - levels[0])
    grid = np.linspace(levels[0] - 2 * span, levels[-1] + 2 * span, 401)
    errors = np.einsum("nr,bgnr->bg", weights, (_mapped(mappings, grid)[None] - c[:, None]) ** 2)
    k = grid[np.argmin(errors, axis=1)]
    derivative = mappings[..., :-1] * np.arange(degree, 0, -1)
    for _ in range(8):
        gap, slope = _mapped(mappings, k) - c, _mapped(derivative, k)  # [B, n, r]
        denominator = np.einsum("nr,bnr->b", weights, slope * slope)
        k = k - np.where(denominator > 0, np.einsum("nr,bnr->b", weights, slope * gap) / np.where(denominator > 0, denominator, 1.0), 0.0)
    return k


# --------------------------------------------------------------------------- the model


@dataclass
class ExaggerationModel:
    """What training finds, with everything needed to exaggerate a new motion and save it.

    ``joint_names [J]``, ``parents [J]``, ``offsets [J, 3]`` (for positions), ``height`` (actor,
    file units), ``hips`` (joint index), ``orders [J, 3]``; ``dof_names [D]``, ``weights [D]``;
    ``levels [K]`` intensities; ``basis [T, r]``, ``singular_values [r]`` (of the kept vectors),
    ``energy`` kept; ``expressiveness [P, D]`` (each person's ``E``, normalised) and ``overall
    [D]`` (their mean); ``key [D]`` bool (union of each person's key set), ``person_key [P, D]``;
    ``mappings [D, r, degree + 1]`` (polynomial in k, highest power first, averaged over
    people); ``reference [J, 4]`` (mean rotations over people); ``lower, upper [D]`` (the range of
    each DOF over every training sample, with rotations measured from ``reference``, the
    parameterisation :func:`exaggerate` edits in by default); ``trajectories [P, K, T, D]`` (the
    training performances, each person's rotations measured from their own mean, for validation),
    ``cycle_trajectories [N, T, D]`` (every cycle they were averaged from) with
    ``cycle_performance [N, 2]`` (the person and intensity index of each); ``person_reference
    [P, J, 4]`` (the people's means).
    """

    joint_names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    height: float
    hips: int
    orders: np.ndarray
    representation: str
    dof_names: tuple[str, ...]
    weights: np.ndarray
    levels: np.ndarray
    basis: np.ndarray
    singular_values: np.ndarray
    energy: float
    expressiveness: np.ndarray
    overall: np.ndarray
    key: np.ndarray
    person_key: np.ndarray
    mappings: np.ndarray
    reference: np.ndarray
    person_reference: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    trajectories: np.ndarray
    cycle_trajectories: np.ndarray
    cycle_performance: np.ndarray
    settings: dict = field(default_factory=dict)

    # ------------------------------------------------------------ derived

    @property
    def n_dofs(self) -> int:
        return len(self.dof_names)

    @property
    def zero_weight_joints(self) -> list[str]:
        """Joints whose bones below have zero length: weight 0, never key features."""
        w = self.weights[:-1].reshape(-1, 3)[:, 0]
        return [n for n, v in zip(self.joint_names, w) if v == 0.0]

    def dof_range(self, reference: str = "model") -> tuple[np.ndarray, np.ndarray]:
        """The lowest and highest value ``[D]`` of each DOF over every training sample, measured as
        :func:`exaggerate` measures a motion with ``reference``: from the people's mean rotations
        (``"model"``: :attr:`lower`, :attr:`upper`) or each from its own mean (``"own"``)."""
        if reference == "own":
            return self.cycle_trajectories.min(axis=(0, 1)), self.cycle_trajectories.max(axis=(0, 1))
        return self.lower, self.upper

    def cycles_of(self, people: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """The training cycles of ``people`` (increasing indices), in the form :func:`fit` takes for
        the trajectories ``self.trajectories[people]``: the people renumbered 0, 1, ..."""
        people = np.asarray(people, dtype=np.int64)
        chosen = np.isin(self.cycle_performance[:, 0], people)
        owners = self.cycle_performance[chosen].copy()
        owners[:, 0] = np.searchsorted(people, owners[:, 0])
        return self.cycle_trajectories[chosen], owners

    def joint_of(self, d: int) -> str:
        return self.dof_names[d].split(".")[0]

    def joint_expressiveness(self, values: np.ndarray | None = None) -> dict[str, float]:
        """``E`` summed per joint (the hips height counted as its own row ``Hips.height``)."""
        values = self.overall if values is None else values
        out: dict[str, float] = {}
        for j, name in enumerate(self.joint_names):
            out[name] = float(values[3 * j : 3 * j + 3].sum())
        out["Hips.height"] = float(values[-1])
        return out

    def key_names(self) -> list[str]:
        """Key DOFs, most expressive first."""
        return [self.dof_names[d] for d in np.argsort(-self.overall) if self.key[d]]

    def predict_coefficients(self, k) -> np.ndarray:
        """``f(k) [..., D, r]``: the mapped coefficients at intensity ``k`` (scalar or array)."""
        return _mapped(self.mappings, k)

    def coefficient_spread(self) -> np.ndarray:
        """``[D, r]``: the mean square distance of the training performances' coefficients from the
        mapping at their own intensity (over people and intensities): what the mappings do not
        predict, the people's differences and the lines' misfit alike."""
        coefficients = np.einsum("tr,pktd->pkdr", self.basis, self.trajectories)
        return ((coefficients - self.predict_coefficients(self.levels)[None]) ** 2).mean(axis=(0, 1))

    def estimate(self, coefficients: np.ndarray, cycle_coefficients: np.ndarray | None = None) -> IntensityEstimate:
        """The current intensity of a motion from its coefficients ``[D, r]`` (the mean over its
        cycles): weighted least squares over the mapped coefficients of the key DOFs, each weighted
        by the inverse of its :meth:`coefficient_spread` (a coefficient the mapping predicts well
        counts more; unweighted, the dataset-2 walks' own 'normal' takes came out at 1.43 for 2).
        ``cycle_coefficients [C, D, r]`` (each cycle's) give the uncertainty its bootstrap part;
        see :class:`IntensityEstimate`."""
        key = self.key
        mappings, c = self.mappings[key], np.asarray(coefficients, dtype=np.float64)[key]
        # No coefficient counts as predicted better than to a tenth of the typical change over the
        # trained range: training data exactly on the lines (one noiseless person) would otherwise
        # weigh in without bound; with that floor alone the weights are equal (plain least squares).
        change = _mapped(mappings, self.levels[-1]) - _mapped(mappings, self.levels[0])
        floor = 0.01 * float(np.mean(change**2)) if change.size else 0.0
        spread = self.coefficient_spread()[key] + (floor if floor > 0 else 1.0)
        weights = 1.0 / spread
        k = float(_weighted_intensity(mappings, weights, c[None], self.levels)[0])
        # Leave one key joint out (its DOFs together: they move together) ...
        joints = np.flatnonzero(key) // 3
        groups = [joints == j for j in np.unique(joints)]
        if len(groups) > 1:
            left_out = np.array([_weighted_intensity(mappings, weights * ~g[:, None], c[None], self.levels)[0] for g in groups])
            n = len(groups)
            jackknife = float(np.sqrt((n - 1) / n * np.sum((left_out - left_out.mean()) ** 2)))
        else:
            jackknife = 0.0
        # ... and resample the motion's cycles.
        bootstrap = 0.0
        if cycle_coefficients is not None and len(cycle_coefficients) > 1:
            cycles = np.asarray(cycle_coefficients, dtype=np.float64)[:, key]
            draws = np.random.default_rng(0).integers(0, len(cycles), size=(BOOTSTRAP_DRAWS, len(cycles)))
            bootstrap = float(np.std(_weighted_intensity(mappings, weights, cycles[draws].mean(axis=1), self.levels)))
        # ... and how far the training performances themselves come out from their intensities.
        trained = np.einsum("tr,pktd->pkdr", self.basis, self.trajectories)[:, :, key]
        P, K = trained.shape[:2]
        trained = trained.reshape(P * K, *trained.shape[2:])
        trained_k = _weighted_intensity(mappings, weights, trained, self.levels)
        training = float(np.sqrt(np.mean((trained_k - np.tile(self.levels, P)) ** 2)))

        def misfit(c: np.ndarray, k: np.ndarray) -> np.ndarray:  # weighted RMS distance from the mapping at k
            return np.sqrt(np.einsum("nr,bnr->b", weights, (_mapped(mappings, k) - c) ** 2) / weights.sum())

        # The residual in units of the training performances' own (at least the floor's tenth of the change).
        typical = max(float(np.sqrt(np.mean(misfit(trained, trained_k) ** 2))), np.sqrt(floor))
        residual = float(misfit(c[None], np.array([k]))[0] / typical) if typical > 0 else 0.0
        return IntensityEstimate(k, float(np.sqrt(jackknife**2 + bootstrap**2 + training**2)), residual, jackknife, bootstrap, training,
                                 (float(self.levels[0]), float(self.levels[-1])))

    def estimate_intensity(self, coefficients: np.ndarray) -> float:
        """:meth:`estimate`'s intensity alone."""
        return self.estimate(coefficients).k

    def table(self, top: int | None = None) -> str:
        """The ranking as text: DOFs (most expressive first, key ones marked) then joints."""
        order = np.argsort(-self.overall)
        cumulative = np.cumsum(self.overall[order])
        lines = [f"{'DOF':<18} {'E':>7} {'cum.':>6}  key"]
        for n, d in enumerate(order[: top or len(order)]):
            lines.append(f"{self.dof_names[d]:<18} {self.overall[d]:7.4f} {cumulative[n]:6.3f}  {'*' if self.key[d] else ''}")
        lines.append("")
        lines.append(f"{'joint':<18} {'E':>7}")
        for name, value in sorted(self.joint_expressiveness().items(), key=lambda kv: -kv[1]):
            lines.append(f"{name:<18} {value:7.4f} {'#' * int(round(value * 60))}")
        zero = self.zero_weight_joints
        if zero:
            lines.append(f"weight 0 (no bone below them, never key features): {', '.join(zero)}")
        lines.append(
            f"{int(self.key.sum())} key DOFs of {self.n_dofs} ({self.key.mean():.0%}) at share {self.settings.get('share', 0.9):g}; "
            f"basis: {self.basis.shape[1]} of {self.basis.shape[0]} vectors ({self.energy:.1%} of the energy); "
            f"{self.expressiveness.shape[0]} person(s), intensities {', '.join(f'{k:g}' for k in self.levels)}"
        )
        return "\n".join(lines)

    def plot(self, path: str | os.PathLike, title: str = "") -> None:
        """A bar plot like the paper's Figure 1 (bottom): expressiveness per DOF, grouped by joint in
        skeleton order, key DOFs dark; below it the per-joint sums. PNG, written atomically."""
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, (top, bottom) = plt.subplots(2, 1, figsize=(12, 6.5))
        x = np.arange(self.n_dofs)
        top.bar(x, self.overall, color=np.where(self.key, "tab:red", "0.7"), width=0.85)
        top.set_xticks(np.arange(1, self.n_dofs, 3), [n for n in self.joint_names] + [], rotation=70, fontsize=7)
        top.set_ylabel("expressiveness E (per DOF)")
        top.set_title(title or "expressiveness per DOF (red: key features)", fontsize=10, loc="left")
        per_joint = self.joint_expressiveness()
        names = list(per_joint)
        key_joints = {self.joint_of(d) if not self.dof_names[d].endswith("height") else "Hips.height" for d in np.flatnonzero(self.key)}
        bottom.bar(np.arange(len(names)), list(per_joint.values()), color=["tab:red" if n in key_joints else "0.7" for n in names])
        bottom.set_xticks(np.arange(len(names)), names, rotation=70, fontsize=7)
        bottom.set_ylabel("expressiveness per joint")
        for ax in (top, bottom):
            for side in ("top", "right"):
                ax.spines[side].set_visible(False)
        fig.tight_layout()
        buffer = io.BytesIO()
        fig.savefig(buffer, format="png", dpi=110)
        plt.close(fig)
        atomic_write(path, buffer.getvalue())

    # ------------------------------------------------------------ files

    _ARRAYS = (
        "parents", "offsets", "orders", "weights", "levels", "basis", "singular_values", "expressiveness", "overall", "key",
        "person_key", "mappings", "reference", "person_reference", "lower", "upper", "trajectories", "cycle_trajectories",
        "cycle_performance",
    )

    def to_bytes(self) -> bytes:
        meta = {
            "format": FORMAT,
            "version": VERSION,
            "joint_names": list(self.joint_names),
            "dof_names": list(self.dof_names),
            "height": self.height,
            "hips": self.hips,
            "representation": self.representation,
            "energy": self.energy,
            "settings": self.settings,
        }
        arrays = {name: np.asarray(getattr(self, name)) for name in self._ARRAYS}
        buffer = io.BytesIO()
        np.savez_compressed(buffer, meta=np.array(json.dumps(meta)), **arrays)
        return buffer.getvalue()

    def save(self, path: str | os.PathLike) -> None:
        """Write the model as ``.npz`` (plain arrays + one JSON string), atomically."""
        atomic_write(path, self.to_bytes())

    @classmethod
    def load(cls, source: str | os.PathLike | bytes) -> ExaggerationModel:
        """Read a model file written by :meth:`save` (``allow_pickle=False``; every array's shape is
        checked against the metadata, with a one-line error naming what is wrong)."""
        arrays, meta, name = read_model_file(source, "exaggeration model")
        if meta.get("format") != FORMAT or meta.get("version") != VERSION:
            raise MocapError(f"{name}: not an expressive-mocap exaggeration model of version {VERSION}")
        check_keys(arrays, cls._ARRAYS, name)
        try:
            for key in ("joint_names", "dof_names"):
                if not isinstance(meta[key], list) or not all(isinstance(n, str) for n in meta[key]):
                    raise MocapError(f"{name}: the metadata's {key} must be a list of names")
            if not isinstance(meta.get("settings", {}), dict):
                raise MocapError(f"{name}: the metadata's settings must be a JSON object")
            J, D = len(meta["joint_names"]), len(meta["dof_names"])
            for key, ndim in (("basis", 2), ("trajectories", 4), ("mappings", 3), ("cycle_trajectories", 3)):
                if finite_array(arrays, key, name, kinds="f").ndim != ndim:
                    raise MocapError(f"{name}: {key!r} has shape {list(arrays[key].shape)}, expected {ndim} dimensions")
            T, r = arrays["basis"].shape
            P, K = arrays["trajectories"].shape[:2]
            degree = arrays["mappings"].shape[-1]
            N = arrays["cycle_trajectories"].shape[0]
            shapes = {
                "parents": (J,), "offsets": (J, 3), "orders": (J, 3), "weights": (D,), "levels": (K,), "basis": (T, r),
                "singular_values": (r,), "expressiveness": (P, D), "overall": (D,), "key": (D,), "person_key": (P, D),
                "mappings": (D, r, degree), "reference": (J, 4), "person_reference": (P, J, 4), "lower": (D,), "upper": (D,),
                "trajectories": (P, K, T, D), "cycle_trajectories": (N, T, D), "cycle_performance": (N, 2),
            }
            for key, shape in shapes.items():
                finite_array(arrays, key, name, shape, kinds="fiub")
            owners = arrays["cycle_performance"]
            if owners.dtype.kind not in "iu" or not ((owners >= 0) & (owners < [P, K])).all() or len(np.unique(owners[:, 0] * K + owners[:, 1])) != P * K:
                raise MocapError(f"{name}: 'cycle_performance' must give every cycle a person < {P} and an intensity index < {K}, and every performance a cycle")
            if D != 3 * J + 1 or not isinstance(meta["representation"], str) or meta["representation"] not in REPRESENTATIONS:
                raise MocapError(f"{name}: {D} DOFs for {J} joints in representation {meta['representation']!r}")
            parents, orders = arrays["parents"].tolist(), arrays["orders"].tolist()
            tree = all(p == -1 if j == 0 else p in range(j) for j, p in enumerate(parents))
            if not tree or any(sorted(o) != [0, 1, 2] for o in orders) or int(meta["hips"]) not in range(J):
                raise MocapError(f"{name}: the skeleton is inconsistent (parents must each come before their joint, orders be axis permutations, hips a joint)")
            return cls(
                joint_names=tuple(meta["joint_names"]), dof_names=tuple(meta["dof_names"]), height=float(meta["height"]),
                hips=int(meta["hips"]), representation=meta["representation"], energy=float(meta["energy"]),
                settings=dict(meta.get("settings", {})),
                **{k: (arrays[k].astype(bool) if k in ("key", "person_key") else arrays[k]) for k in cls._ARRAYS},
            )
        except KeyError as error:
            raise MocapError(f"{name}: model file lacks {error}") from None
        except MocapError:
            raise
        except (TypeError, ValueError) as error:  # metadata of the wrong types, e.g. "height": "tall"
            raise MocapError(f"{name}: invalid metadata ({type(error).__name__}: {error})") from None

    def check_skeleton(self, motion: Motion) -> None:
        if motion.skeleton.names != self.joint_names:
            raise MocapError(
                f"the model was trained on a {len(self.joint_names)}-joint skeleton ({', '.join(self.joint_names[:3])}, ...); "
                f"the motion has {motion.skeleton.n_joints} joints ({', '.join(motion.skeleton.names[:3])}, ...)"
            )


# --------------------------------------------------------------------------- training


@dataclass
class _PersonDofs:
    """One person's training DOFs: each performance's trajectory ``[K, T, D]`` (the mean of its
    cycles in DOF space), every cycle ``[N, T, D]`` with its performance's index ``[N]``, and the
    person's mean rotations ``[J, 4]`` (over every sample of every clip) they are measured from."""

    performances: np.ndarray
    cycles: np.ndarray
    cycle_level: np.ndarray
    reference: np.ndarray


def _person_dofs(motions: Sequence[Motion], roles: JointRoles, samples: int, cycle, representation: str, foot: int) -> _PersonDofs:
    sampled = []
    for k, m in enumerate(motions):
        try:
            sampled.append(_sample_cycles(m, roles, _choose_cycles(m, roles, cycle, foot), samples))
        except MocapError as error:  # which clip: the caller knows the person, and maybe the file
            raise ClipError(str(error), -1, k) from None
    everything = np.concatenate([s.rotations.reshape(-1, *s.rotations.shape[2:]) for s in sampled])
    reference = mean_rotation(everything)
    orders = motions[0].skeleton.euler_orders
    per_clip = []
    for s in sampled:
        C, T, J, _ = s.rotations.shape
        rot = rotations_to_dofs(s.rotations.reshape(C * T, J, 4), reference, representation, orders).reshape(C, T, 3 * J)
        per_clip.append(np.concatenate([rot, s.heights[..., None]], axis=-1))
    return _PersonDofs(
        performances=np.stack([c.mean(axis=0) for c in per_clip]),
        cycles=np.concatenate(per_clip),
        cycle_level=np.repeat(np.arange(len(per_clip)), [len(c) for c in per_clip]),
        reference=reference,
    )


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
    return np.where(denominator > 1e-12 * max(1.0, float(np.abs(c).max(initial=0.0))), (dc * dk).sum(axis=0) / np.where(denominator > 0, denominator, 1.0), 0.0)


def _mapped(mappings: np.ndarray, k) -> np.ndarray:
    """``f(k) [..., D, r]``: polynomial mappings ``[D, r, degree + 1]`` (highest power first) at ``k``."""
    k = np.asarray(k, dtype=np.float64)
    return np.einsum("dip,...p->...di", mappings, k[..., None] ** np.arange(mappings.shape[-1] - 1, -1, -1))


def _single_cycles(trajectories: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each performance of ``trajectories [P, K, T, D]`` as its only cycle: ``(cycles [P K, T, D],
    performance [P K, 2])``."""
    P, K, T, D = trajectories.shape
    return trajectories.reshape(P * K, T, D), np.stack(np.unravel_index(np.arange(P * K), (P, K)), axis=1)


def _cycle_correlation(basis: np.ndarray, cycles: tuple[np.ndarray, np.ndarray], levels: np.ndarray, people: int) -> np.ndarray:
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
    share: float = 0.9,
    energy: float = 0.99,
    rank: int | None = None,
    degree: int = 1,
) -> dict:
    """The method on DOF trajectories ``[P, K, T, D]`` at intensities ``levels [K]`` with DOF
    weights ``[D]``: basis, expressiveness, key sets, mappings. ``cycles``: every cycle the
    performances were averaged from, ``(trajectories [N, T, D], performance [N, 2])`` (person and
    intensity index of each), over which predictability is measured; by default each performance
    is its only cycle. Returns a dict of the model's arrays (``basis, singular_values, energy,
    expressiveness, overall, key, person_key, mappings``)."""
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
    return {
        "basis": U,
        "singular_values": s,
        "energy": float(np.sum(s * s) / max(total, 1e-300)),
        "expressiveness": E,
        "overall": E.mean(axis=0),
        "key": person_key.any(axis=0),
        "person_key": person_key,
        "mappings": mappings,
    }


def train(
    people: Sequence[Sequence[Motion]],
    levels: Sequence[float],
    *,
    samples: int = 50,
    share: float = 0.9,
    energy: float = 0.99,
    rank: int | None = None,
    degree: int = 1,
    representation: str = "rotvec",
    cycle: str | int | tuple = "all",
    foot: int = 0,
    roles: JointRoles | None = None,
) -> ExaggerationModel:
    """Rank the expressive features of one action and fit the intensity mappings.

    ``people[p][k]`` is person ``p``'s performance at intensity ``levels[k]`` (one list per person;
    one person is ``[[light, medium, heavy]]``). ``cycle`` picks each clip's cycles (see
    :func:`_choose_cycles`): "all" by default (the performance is their mean; predictability is
    measured over every one), "middle" for the paper's single cycle, "whole" or ``(start, end)`` for
    actions that are not walks. ``samples`` is ``T``; ``energy`` the basis' share of ``sum(s^2)`` unless
    ``rank`` is given; ``share`` the expressiveness accumulated into the key set; ``degree`` the
    mappings' polynomial degree (< number of intensities); ``foot`` (0 = left, 1 = right) the foot
    whose footstrikes start a walking cycle, here and in :func:`exaggerate` (the basis is phase-aligned
    to it).
    """
    people = [list(p) for p in people]
    levels = np.asarray(levels, dtype=np.float64).reshape(-1)
    K = len(levels)
    if K < 2 or not np.all(np.diff(levels) > 0) or not np.isfinite(levels).all():
        raise MocapError(f"intensities must be at least two increasing numbers, got {levels.tolist()}")
    if not people or any(len(p) != K for p in people):
        raise MocapError(f"each person needs one clip per intensity ({K}); got {[len(p) for p in people]}")
    if representation not in REPRESENTATIONS:
        raise MocapError(f"representation must be one of {', '.join(REPRESENTATIONS)}, got {representation!r}")
    if not 0 < share <= 1 or not 0 < energy <= 1:
        raise MocapError(f"share and energy must be in (0, 1], got {share} and {energy}")
    if not 0 <= int(degree) < K:
        raise MocapError(f"degree {degree}: a polynomial mapping needs fewer degrees than intensities ({K})")
    if int(samples) < 3:
        raise MocapError(f"samples (T) must be at least 3, got {samples}")
    if foot not in (0, 1):
        raise MocapError(f"foot must be 0 (left) or 1 (right), got {foot!r}")
    for m in (m for p in people for m in p):
        if not isinstance(m, Motion):
            raise MocapError(f"expected Motion objects, got {type(m).__name__}")
    skeleton = people[0][0].skeleton
    for i, person in enumerate(people):
        for k, m in enumerate(person):
            if m.skeleton.names != skeleton.names:
                raise ClipError(f"another skeleton ({m.skeleton.n_joints} joints, {', '.join(m.skeleton.names[:3])}, ...) than the "
                                f"first clip's ({skeleton.n_joints} joints, {', '.join(skeleton.names[:3])}, ...): a model is trained "
                                "on clips of one skeleton", i, k)
    roles = roles or JointRoles.find(skeleton)
    per_person = []
    for i, person in enumerate(people):
        try:
            per_person.append(_person_dofs(person, roles, int(samples), cycle, representation, int(foot)))
        except ClipError as error:
            raise ClipError(str(error), i, error.level) from None
    X = np.stack([d.performances for d in per_person])
    refs = np.stack([d.reference for d in per_person])
    cycle_trajectories = np.concatenate([d.cycles for d in per_person])
    cycle_performance = np.concatenate([np.stack([np.full(len(d.cycles), p), d.cycle_level], axis=1) for p, d in enumerate(per_person)])
    w = subtree_weights(skeleton)
    weights = np.append(np.repeat(w, 3), w[0] if skeleton.parents[roles.hips] < 0 else w[roles.hips])
    fitted = fit(X, levels, weights, cycles=(cycle_trajectories, cycle_performance), share=share, energy=energy, rank=rank, degree=int(degree))
    reference = mean_rotation(refs)
    # The training range in the parameterisation a new motion is edited in: every cycle's
    # rotations from the people's mean (each person's are measured from their own mean, which may
    # differ by degrees).
    orders = np.asarray(skeleton.euler_orders).astype(np.int64)
    J = skeleton.n_joints
    common = np.concatenate(
        [rotations_to_dofs(dofs_to_rotations(d.cycles[..., :-1].reshape(-1, 3 * J), d.reference, representation, orders), reference, representation, orders)
         for d in per_person]
    )
    common = np.concatenate([common, cycle_trajectories[..., -1].reshape(-1, 1)], axis=1)
    return ExaggerationModel(
        joint_names=skeleton.names,
        parents=np.asarray(skeleton.parents),
        offsets=np.asarray(skeleton.offsets),
        height=actor_height(skeleton, roles),
        hips=roles.hips,
        orders=orders,
        representation=representation,
        dof_names=tuple(dof_names(skeleton, representation)),
        weights=weights,
        levels=levels,
        reference=reference,
        person_reference=refs,
        lower=common.min(axis=0),
        upper=common.max(axis=0),
        trajectories=X,
        cycle_trajectories=cycle_trajectories,
        cycle_performance=cycle_performance,
        settings={"samples": int(samples), "share": share, "energy": energy, "rank": rank, "degree": int(degree), "cycle": str(cycle), "foot": int(foot)},
        **fitted,
    )


# --------------------------------------------------------------------------- exaggeration


@dataclass
class ExaggerationReport:
    """What :func:`exaggerate` did: intensities (``k0`` estimated or given), cycles edited, DOFs clamped
    (``{dof: (frames, largest excess)}``), the largest rotation change per joint (degrees), foot
    locking's largest ankle correction, the largest distance it could not close and how far it lowered the hips (file units),
    stance-foot speeds before and after; ``estimate`` how ``k0`` was estimated (None when given)."""

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

    def text(self) -> str:
        e = self.estimate
        k0 = f"{self.k0:.3g} +- {e.uncertainty:.2g} (estimated)" if e is not None else f"{self.k0:.3g}"
        lines = [
            f"intensity {k0} -> {self.k1:.3g}; {len(self.cycles)} cycle(s) edited"
            + (f" (frames {self.cycles[0].start}-{self.cycles[-1].end})" if self.cycles else ""),
        ]
        if e is not None:
            lines.append(
                f"estimate: fit residual {e.residual:.2f} (the training performances' own: about 1); uncertainty from the key joints "
                f"{e.jackknife:.2g}, the cycles {e.bootstrap:.2g}, the training clips' own error {e.training:.2g}"
            )
            if e.warning():
                lines.append("warning: " + e.warning())
        if self.clamped:
            worst = sorted(self.clamped.items(), key=lambda kv: -kv[1][1])
            lines.append(
                f"clamped to the training range (+margin), {len(worst)} DOF(s): "
                + ", ".join(f"{d} ({n} frames, by up to {_amount(d, v)})" for d, (n, v) in worst[:8])
            )
        else:
            lines.append("nothing clamped")
        changes = sorted(self.largest_change.items(), key=lambda kv: -kv[1])
        lines.append("largest change per joint (degrees): " + ", ".join(f"{n} {v:.1f}" for n, v in changes if v >= 0.05)[:600] or "largest change: none")
        lines.append(
            f"stance-foot speed {self.stance_speed_input:.3g} -> {self.stance_speed_output:.3g} (file units/s); foot locking moved "
            f"the ankles by up to {self.foot_correction:.3g} (out of reach by up to {self.foot_residual:.3g}), lowering the hips "
            f"by up to {self.hips_lowered:.3g} where a leg could not reach"
        )
        return "\n".join(lines)


def _amount(dof: str, value: float) -> str:
    return f"{value:.3f} x height" if dof.endswith(".height") else f"{np.degrees(value):.1f} deg"


def stance_foot_speed(motion: Motion, contacts: np.ndarray, roles: JointRoles | None = None) -> float:
    """Mean horizontal speed (file units per second) of the feet (ankle and toe) over the frames
    where ``contacts [F, 2]`` says they touch the floor."""
    roles = roles or JointRoles.find(motion.skeleton)
    p = motion.positions()
    speeds = []
    for s in (0, 1):
        for joint in (roles.feet[s], roles.toes[s]):
            v = np.linalg.norm(np.diff(p[:, joint, [0, 2]], axis=0), axis=-1) / motion.frame_time
            both = contacts[1:, s] & contacts[:-1, s]
            speeds.append(v[both])
    speeds = np.concatenate(speeds)
    return float(speeds.mean()) if len(speeds) else 0.0


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


def _frame_yaw(motion: Motion, roles: JointRoles, cycles: Sequence[Cycle], positions: np.ndarray) -> np.ndarray:
    """Heading (degrees) of every frame: its cycle's; before the first / after the last, the nearest."""
    yaw = np.zeros(motion.n_frames)
    if not cycles:
        return yaw + cycle_heading(motion, roles, Cycle(0, motion.n_frames - 1), positions)
    headings = [cycle_heading(motion, roles, c, positions) for c in cycles]
    yaw[: cycles[0].start] = headings[0]
    for c, h in zip(cycles, headings):
        yaw[c.start : c.end + 1] = h
    yaw[cycles[-1].end :] = headings[-1]
    return yaw


def motion_dofs(model: ExaggerationModel, motion: Motion, roles: JointRoles, yaw: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """DOFs ``[F, D]`` of every frame of ``motion`` (heading ``yaw [F]`` removed, rotations relative to
    ``reference``; the hips height in units of the motion's own actor height, as in training, so a
    model trained in centimetres edits a motion in metres)."""
    rot = rotations_to_dofs(_without_heading(motion.rotations, roles.hips, yaw), reference, model.representation, model.orders)
    heights = motion.positions()[:, roles.hips, 1] / actor_height(motion.skeleton, roles)
    return np.concatenate([rot, heights[:, None]], axis=1)


def exaggerate(
    model: ExaggerationModel,
    motion: Motion,
    to: float,
    *,
    current: float | None = None,
    cycles: Sequence[Cycle] | None = None,
    reference: str = "model",
    margin: float = 0.1,
    fade: float = 0.15,
    lock_feet: bool = True,
    blend: float = 0.1,
    roles: JointRoles | None = None,
) -> tuple[Motion, ExaggerationReport]:
    """Exaggerate (``to`` above the current intensity) or diminish ``motion`` with ``model``.

    ``current`` is ``k0``; by default (None) it is estimated from the mean coefficients of the
    motion's cycles by least squares over the key DOFs' mapped coefficients, each weighted by how
    well the mapping predicts it (:meth:`ExaggerationModel.estimate`); the report holds the
    estimate with its uncertainty and fit residual, and a ``UserWarning`` says when it is outside
    the trained range. Every cycle (``cycles``: default, the footstrike-to-footstrike cycles of
    the foot the model was trained with; a single whole-clip cycle when none is found) gets ``x' = x + U (f(to) - f(k0))`` on the key DOFs,
    in its own timing; frames outside the cycles keep their values and the changes are cross-faded
    over ``fade`` seconds at every boundary. DOFs are kept within the training range widened by
    ``margin`` x its width (never pushed past where they already were). ``reference`` "model"
    measures rotations from the training people's mean pose, "own" from the motion's own mean.
    The DOF range is the one seen in training, measured from the same reference (see
    :meth:`ExaggerationModel.dof_range`). ``lock_feet`` pins each stance foot (ankle position and
    foot orientation) to the input's during its contacts with two-bone leg IK, blended in and out
    over ``blend`` seconds, so the edit adds no skating (see :func:`lock_stance_feet`). Returns
    the new motion and an :class:`ExaggerationReport`.
    """
    if not isinstance(motion, Motion):
        raise MocapError(f"argument `motion`: expected a Motion, got {type(motion).__name__}")
    model.check_skeleton(motion)
    if not np.isfinite(to) or (current is not None and not np.isfinite(current)):
        raise MocapError(f"intensities must be finite numbers, got to={to}, current={current}")
    if reference not in ("model", "own"):
        raise MocapError(f"reference must be 'model' or 'own', got {reference!r}")
    if motion.n_frames < 3:
        raise MocapError(f"a motion of {motion.n_frames} frames is too short to exaggerate")
    if not (np.isfinite(margin) and margin >= 0) or not (np.isfinite(fade) and fade >= 0) or not (np.isfinite(blend) and blend >= 0):
        raise MocapError(f"margin, fade and blend must be finite numbers >= 0, got margin={margin}, fade={fade}, blend={blend}")
    roles = roles or JointRoles.find(motion.skeleton)
    contacts = foot_contacts(motion, roles)
    if cycles is None:
        cycles = find_cycles(motion, roles, contacts, foot=int(model.settings.get("foot", 0))) or [Cycle(0, motion.n_frames - 1)]
    cycles = list(cycles)
    positions = motion.positions()
    yaw = _frame_yaw(motion, roles, cycles, positions)
    T = model.basis.shape[0]
    if reference == "own":
        hf = _without_heading(motion.rotations, roles.hips, yaw)
        ref = mean_rotation(hf[cycles[0].start : cycles[-1].end + 1])
    else:
        ref = model.reference
    X = motion_dofs(model, motion, roles, yaw, ref)  # [F, D]
    # Coefficients of each cycle's normalised trajectories (same sampling as training).
    sampled = _sample_cycles(motion, roles, cycles, T)
    C, _, J, _ = sampled.rotations.shape
    rot = rotations_to_dofs(sampled.rotations.reshape(C * T, J, 4), ref, model.representation, model.orders).reshape(C, T, 3 * J)
    cycle_dofs = np.concatenate([rot, sampled.heights[..., None]], axis=-1)
    per_cycle = np.einsum("tr,ctd->cdr", model.basis, cycle_dofs)
    estimated = current is None
    estimate = model.estimate(per_cycle.mean(axis=0), per_cycle) if estimated else None
    k0 = estimate.k if estimated else float(current)
    if estimated and estimate.warning():
        warnings.warn(estimate.warning(), stacklevel=2)
    change = (model.predict_coefficients(float(to)) - model.predict_coefficients(k0)) * model.key[:, None]  # [D, r]
    delta = model.basis @ change.T  # [T, D]
    per_frame = _per_frame_change(delta, cycles, motion.n_frames, int(round(fade * motion.fps)))
    target = X + per_frame
    # Plausibility: the training range (in the same parameterisation as X), widened by the margin,
    # and never tighter than the input itself.
    lower, upper = model.dof_range(reference)
    width = upper - lower
    low = np.minimum(lower - margin * width, X)
    high = np.maximum(upper + margin * width, X)
    clamped_values = np.clip(target, low, high)
    excess = np.abs(clamped_values - target)
    clamped = {model.dof_names[d]: (int(np.count_nonzero(excess[:, d] > 1e-12)), float(excess[:, d].max())) for d in np.flatnonzero(excess.max(axis=0) > 1e-12)}
    new = clamped_values
    changed = np.flatnonzero(np.abs(new - X).max(axis=0) > 0)
    rotations = motion.rotations.copy()
    translations = motion.translations.copy()
    joints = sorted({int(d) // 3 for d in changed if d < 3 * J})
    if joints:
        rebuilt = dofs_to_rotations(new[:, : 3 * J], ref, model.representation, model.orders)
        rebuilt[:, roles.hips] = quat.mul(quat.about("Y", yaw), rebuilt[:, roles.hips])  # the heading back
        rotations[:, joints] = rebuilt[:, joints]
    world_rotations, _ = forward_kinematics(motion.rotations, motion.translations, motion.skeleton.parents)
    parent = motion.skeleton.parents[roles.hips]
    parent_rot = world_rotations[:, parent] if parent >= 0 else np.broadcast_to(IDENTITY, (motion.n_frames, 4))
    lift = np.zeros((motion.n_frames, 3))
    lift[:, 1] = (new[:, -1] - X[:, -1]) * actor_height(motion.skeleton, roles)  # the motion's units, not the model's
    translations[:, roles.hips] += quat.rotate(quat.conjugate(parent_rot), lift)
    out = Motion(motion.skeleton, rotations, translations, motion.frame_time)
    correction = residual = lowered = 0.0
    if lock_feet and len(changed):
        out, correction, residual, lowered = lock_stance_feet(motion, out, contacts, roles, int(round(blend * motion.fps)))
        rotations = out.rotations
    angles = np.degrees(quat.angle(quat.mul(quat.conjugate(motion.rotations), rotations))).max(axis=0)
    report = ExaggerationReport(
        k0=k0, k1=float(to), k0_estimated=estimated, cycles=cycles, clamped=clamped, estimate=estimate,
        largest_change={n: float(a) for n, a in zip(motion.skeleton.names, angles)},
        foot_correction=correction,
        foot_residual=residual,
        hips_lowered=lowered,
        stance_speed_input=stance_foot_speed(motion, contacts, roles),
        stance_speed_output=stance_foot_speed(out, contacts, roles),
    )
    return out, report


def _contact_weights(contacts: np.ndarray, frames: int) -> np.ndarray:
    """Locking weights ``[F, S]`` from ``contacts bool [F, S]``: 1 in contact, easing to 0 over
    ``frames`` frames before and after each contact (smoothstep of the distance in frames)."""
    F = len(contacts)
    linear = contacts.astype(np.float64)
    for i in range(1, frames + 1):
        ramp = 1.0 - i / (frames + 1)
        linear[i:] = np.maximum(linear[i:], ramp * contacts[:-i])
        linear[:-i] = np.maximum(linear[:-i], ramp * contacts[i:])
    return linear * linear * (3 - 2 * linear) if F else linear


def lock_stance_feet(original: Motion, edited: Motion, contacts: np.ndarray, roles: JointRoles, blend_frames: int = 3) -> tuple[Motion, float, float]:
    """``edited`` with each foot put back where ``original`` has it while it touches the floor.

    For each side, in the frames where the foot's locking weight ``w`` (1 in the contacts
    ``[F, 2]``, eased to 0 over ``blend_frames`` frames either side) is above 0, the ankle's
    target is ``(1 - w) edited + w original`` (world positions) and the foot's world rotation the
    slerp between the two by ``w``; two-bone IK (:func:`~expressive_mocap.ik.two_bone_ik`) turns
    the upper and lower leg to reach the target, and the foot's local rotation is set to give the
    wanted world rotation. The toe, fixed to the foot, follows. Where a target is beyond the leg's
    reach (the edit raised the hips or spread the legs), the hips are first lowered just enough,
    eased in and out over ``blend_frames``: a stance foot is never lifted off the floor.

    Returns the new motion, the largest distance an ankle was moved to its target, the largest
    distance left where the target was out of the leg's reach (file units; the hips could not
    help: the target is beyond the leg's length across the floor), and how far the hips were lowered.
    """
    parents = original.skeleton.parents
    for s in (0, 1):
        hip, foot = roles.upper_legs[s], roles.feet[s]
        if parents[foot] < 0 or parents[parents[foot]] != hip:
            names = original.skeleton.names
            raise MocapError(f"foot locking needs a two-bone leg: {names[foot]} is not the grandchild of {names[hip]}; use lock_feet=False")
    world_in, pos_in = forward_kinematics(original.rotations, original.translations, parents)
    weights = _contact_weights(np.asarray(contacts, dtype=bool), blend_frames)
    edited, lowered = _lowered_to_reach(edited, pos_in, weights, roles, blend_frames)
    world_out, pos_out = forward_kinematics(edited.rotations, edited.translations, parents)
    height = actor_height(original.skeleton, roles)  # tolerances in the motion's units
    rotations = edited.rotations.copy()
    correction = 0.0
    legs = []
    for s in (0, 1):
        hip, foot = roles.upper_legs[s], roles.feet[s]
        knee = parents[foot]
        # Frames to lock: weighted, and where the edit moved or turned the foot at all (elsewhere
        # the IK would only add rounding).
        moved = (np.linalg.norm(pos_out[:, foot] - pos_in[:, foot], axis=1) > 1e-11 * height) | (quat.angle(quat.mul(quat.conjugate(world_in[:, foot]), world_out[:, foot])) > 1e-9)
        frames = np.flatnonzero((weights[:, s] > 0) & moved)
        if not len(frames):
            continue
        w = weights[frames, s, None]
        target = (1 - w) * pos_out[frames, foot] + w * pos_in[frames, foot]
        correction = max(correction, float(np.linalg.norm(target - pos_out[frames, foot], axis=1).max()))
        t = edited.translations[frames]
        upper, lower = two_bone_ik(pos_out[frames, hip], world_out[frames, hip], world_out[frames, knee], t[:, knee], t[:, foot], target)
        foot_world = quat.slerp(world_out[frames, foot], world_in[frames, foot], w[:, 0])
        parent = parents[hip]
        parent_world = world_out[frames, parent] if parent >= 0 else np.broadcast_to(IDENTITY, (len(frames), 4))
        rotations[frames, hip] = quat.mul(quat.conjugate(parent_world), upper)
        rotations[frames, knee] = quat.mul(quat.conjugate(upper), lower)
        rotations[frames, foot] = quat.mul(quat.conjugate(lower), foot_world)
        legs.append((frames, foot, target))
    out = Motion(edited.skeleton, rotations, edited.translations, edited.frame_time)
    positions = out.positions()
    residual = max((float(np.linalg.norm(positions[f, foot] - target, axis=1).max()) for f, foot, target in legs), default=0.0)
    return out, correction, residual, lowered


# A leg reaches this share of its length at most: a knee straightened to the last 0.01% would flip.
REACH = 0.9999


def _lowered_to_reach(edited: Motion, pos_in: np.ndarray, weights: np.ndarray, roles: JointRoles, blend_frames: int) -> tuple[Motion, float]:
    """``edited`` with its hips lowered (along the vertical, in file units) in the frames where a
    locked foot's target, the input's ankle, is beyond its leg's reach from where the edit put
    the hip: just enough for the leg to reach it, eased over ``blend_frames`` frames either side
    (a soft dilation of the drop, so the hips never jump). Returns it and the largest drop."""
    parents = edited.skeleton.parents
    world, pos = forward_kinematics(edited.rotations, edited.translations, parents)
    drop = np.zeros(edited.n_frames)
    for s in (0, 1):
        hip, foot = roles.upper_legs[s], roles.feet[s]
        knee = parents[foot]
        frames = np.flatnonzero(weights[:, s] > 0)
        length = REACH * (np.linalg.norm(edited.translations[frames, knee], axis=1) + np.linalg.norm(edited.translations[frames, foot], axis=1))
        target = (1 - weights[frames, s, None]) * pos[frames, foot] + weights[frames, s, None] * pos_in[frames, foot]
        above = pos[frames, hip] - target
        across = np.hypot(above[:, 0], above[:, 2])
        # The hip must come within reach, |above - d up| = length; lowering the hips by `drop` lowers
        # the edited foot too, so the target (a blend of it and the input's ankle) by (1 - w) drop:
        # d = w drop.
        needed = above[:, 1] - np.sqrt(np.clip(length**2 - across**2, 0.0, None))
        drop[frames] = np.maximum(drop[frames], np.clip(needed, 0.0, None) / weights[frames, s])
    if not drop.any():
        return edited, 0.0
    eased = drop.copy()
    for i in range(1, blend_frames + 1):
        x = 1.0 - i / (blend_frames + 1)
        ramp = x * x * (3 - 2 * x)
        eased[i:] = np.maximum(eased[i:], ramp * drop[:-i])
        eased[:-i] = np.maximum(eased[:-i], ramp * drop[i:])
    hips, parent = roles.hips, parents[roles.hips]
    parent_rot = world[:, parent] if parent >= 0 else np.broadcast_to(IDENTITY, (edited.n_frames, 4))
    down = np.zeros((edited.n_frames, 3))
    down[:, 1] = -eased
    translations = edited.translations.copy()
    translations[:, hips] += quat.rotate(quat.conjugate(parent_rot), down)
    return Motion(edited.skeleton, edited.rotations, translations, edited.frame_time), float(eased.max())


# --------------------------------------------------------------------------- validation


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


def _ratios(model: ExaggerationModel, light: np.ndarray, heavy: np.ndarray, reference: np.ndarray, sets: Sequence[np.ndarray]) -> np.ndarray:
    """``[len(sets), 2]``: DOF and position ratios after swapping each set of DOFs light -> heavy."""
    hp = dof_positions(model, heavy, reference)
    base = np.linalg.norm(light - heavy), np.linalg.norm(dof_positions(model, light, reference) - hp)
    out = []
    for dofs in sets:
        swap = light.copy()
        swap[:, dofs] = heavy[:, dofs]
        out.append((np.linalg.norm(swap - heavy) / base[0], np.linalg.norm(dof_positions(model, swap, reference) - hp) / base[1]))
    return np.array(out)


def swap_test(model: ExaggerationModel, person: int | None = None, *, draws: int = 200, seed: int = 0, union_key: np.ndarray | None = None) -> list[SwapResult]:
    """Swap the key DOF trajectories of each person's lightest performance for the heaviest's
    and compare with the real heaviest (the paper's own validation). ``person``: one index, or every
    person (their own key sets) followed by ``"union"`` (every person with the union key set
    ``union_key``, by default :attr:`ExaggerationModel.key`; the people's ratios averaged)."""
    P, K, T, D = model.trajectories.shape
    rng = np.random.default_rng(seed)
    people = range(P) if person is None else [int(person)]
    results = []

    def run(label: str, pairs: list[int], key: np.ndarray) -> SwapResult:
        n = int(key.sum())
        numbers = []
        for p in pairs:
            light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
            difference = np.linalg.norm(light - heavy, axis=0)
            sets = [np.flatnonzero(key), np.argsort(-difference)[:n]] + [rng.choice(D, n, replace=False) for _ in range(draws)]
            numbers.append(_ratios(model, light, heavy, model.person_reference[p], sets))
        r = np.mean(numbers, axis=0)
        return SwapResult(label, n, n / D, r[0, 0], r[0, 1], float(r[2:, 0].mean()), float(r[2:, 1].mean()), r[1, 0], r[1, 1])

    for p in people:
        if not 0 <= p < P:
            raise MocapError(f"person {p}: the model has {P} people")
        results.append(run(str(p), [p], model.person_key[p]))
    if person is None and P > 1:
        key = model.key if union_key is None else np.asarray(union_key, dtype=bool)
        if key.shape != (D,):
            raise MocapError(f"argument `union_key`: expected {D} booleans, got shape {list(key.shape)}")
        results.append(run("union", list(range(P)), key))
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
            f"rank agreement between people (Spearman, every pair): mean {self.mean:.3f} (lowest {self.lowest:.3f}) over the "
            f"{self.dofs} DOFs with E > 0 for someone; {self.mean_all:.3f} over all DOFs"
        )


def rank_agreement(model: ExaggerationModel) -> RankAgreement:
    """How much the people agree on the ranking (needs at least two people)."""
    from scipy.stats import spearmanr

    E = model.expressiveness
    P = len(E)
    if P < 2:
        raise MocapError("rank agreement needs at least two people")
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
        raise MocapError("leave-one-person-out needs at least two people")
    settings = model.settings
    results = []
    for p in range(P):
        others = [q for q in range(P) if q != p]
        fitted = fit(model.trajectories[others], model.levels, model.weights, cycles=model.cycles_of(others), share=settings.get("share", 0.9), energy=settings.get("energy", 0.99),
                     rank=settings.get("rank"), degree=settings.get("degree", 1))
        change = (_mapped(fitted["mappings"], model.levels[-1]) - _mapped(fitted["mappings"], model.levels[0])) * fitted["key"][:, None]
        light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
        warped = light + fitted["basis"] @ change.T
        reference = model.person_reference[p]
        hp = dof_positions(model, heavy, reference)
        ratio = np.linalg.norm(warped - heavy) / np.linalg.norm(light - heavy)
        positions = np.linalg.norm(dof_positions(model, warped, reference) - hp) / np.linalg.norm(dof_positions(model, light, reference) - hp)
        results.append(WarpResult(str(p), int(fitted["key"].sum()), float(ratio), float(positions)))
    return results


def validation_table(swaps: Sequence[SwapResult], warps: Sequence[WarpResult] = (), agreement: RankAgreement | None = None) -> str:
    """Both tests (and the people's rank agreement) as text."""
    lines = [f"{'person':<8} {'swapped':>11} {'ratio':>7} {'random':>7} {'best':>7} | {'pos.':>6} {'random':>7} {'best':>7}"]
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
        lines.append(f"{'mean':<8} {'':>4} {np.mean([w.ratio for w in warps]):7.3f} {np.mean([w.ratio_positions for w in warps]):7.3f}")
    if agreement is not None:
        lines.append("")
        lines.append(agreement.text())
    return "\n".join(lines)


__all__ = [
    "Cycle",
    "ExaggerationModel",
    "ExaggerationReport",
    "IntensityEstimate",
    "RankAgreement",
    "SwapResult",
    "WarpResult",
    "dof_positions",
    "exaggerate",
    "leave_one_out",
    "swap_test",
    "validation_table",
    "find_cycles",
    "fit",
    "lock_stance_feet",
    "normalise_cycle",
    "rank_agreement",
    "stance_foot_speed",
    "subtree_weights",
    "to_cycle_timing",
    "train",
]
