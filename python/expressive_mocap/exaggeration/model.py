"""The exaggeration model: what training finds (:class:`ExaggerationModel`), the quantities
derived from it, and its file format (``.npz`` of plain arrays plus one JSON object)."""

from __future__ import annotations

import io
import json
import os
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np

from .._utils.files import atomic_write
from .._utils.model_files import check_keys, finite_array, read_model_file
from ..body.body import Body
from ..body.hinges import HingeLimits, learn_hinge_limits
from ..body.take import Take
from ..errors import ArgumentError, MocapError, ModelError
from ..motion import Motion
from .dofs import dofs_to_rotations
from .estimate import IntensityEstimate, estimate_intensity
from .fitting import mapped
from .settings import REPRESENTATIONS, TrainSettings

FORMAT = "expressive-mocap exaggeration model"
# 3: every training cycle kept (cycle_trajectories, cycle_performance); 2: lower / upper measured
# from the people's mean rotations (1: from each person's own)
VERSION = 3

# The arrays of a model file, in the order they are written.
ARRAYS = (
    "parents", "offsets", "orders", "weights", "levels", "basis", "singular_values", "expressiveness", "overall", "key",
    "person_key", "mappings", "reference", "person_reference", "lower", "upper", "trajectories", "cycle_trajectories",
    "cycle_performance",
)  # fmt: skip
# Arrays a model trained with timing adds (a file without them edits without timing).
TIMING_ARRAYS = ("cycle_timing", "timing_mappings", "timing_predictability")
# A compact file (the shipped models): the training cycles cut to a few per performance, and the
# trajectories and cycles in half precision (0.06 degrees on a radian): a walk model's file takes
# 0.4 MB instead of 4.5. They serve validation, the hinge limits and the "own" range only.
COMPACT_CYCLES = 2
COMPACT_ARRAYS = ("trajectories", "cycle_trajectories")


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
    parameterisation :func:`~expressive_mocap.exaggeration.exaggerate` edits in by default);
    ``trajectories [P, K, T, D]`` (the training performances, each person's rotations measured
    from their own mean, for validation), ``cycle_trajectories [N, T, D]`` (every cycle they were
    averaged from) with ``cycle_performance [N, 2]`` (the person and intensity index of each);
    ``person_reference [P, J, 4]`` (the people's means); ``settings`` what training was run with
    (a :class:`TrainSettings`, the defaults where a file has none); ``joint_map`` which joint of its skeleton
    plays which role (a map file's form), by which motions of other skeletons reach the model.
    Timing (:mod:`.timing`; None in a model file written without it): ``cycle_timing [N, 2]``
    each training cycle's log duration (s) and log travel (actor heights), ``timing_mappings
    [2, K]`` the people's mean of each at every trained intensity (followed level to level:
    :func:`~expressive_mocap.exaggeration.timing.mapped_timing`), ``timing_predictability [2]``
    their mean |correlation| with k.
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
    settings: TrainSettings = field(default_factory=TrainSettings)
    joint_map: dict = field(default_factory=dict)  # role -> joint name(s) of its skeleton, as found in training
    cycle_timing: np.ndarray | None = None
    timing_mappings: np.ndarray | None = None
    timing_predictability: np.ndarray | None = None

    _ARRAYS = ARRAYS

    # ------------------------------------------------------------ derived

    @property
    def n_dofs(self) -> int:
        return len(self.dof_names)

    @property
    def training(self) -> TrainSettings:
        """:attr:`settings`, with the model's :attr:`representation`."""
        return replace(self.settings, representation=self.representation)

    @property
    def zero_weight_joints(self) -> list[str]:
        """Joints whose bones below have zero length: weight 0, never key features."""
        w = self.weights[:-1].reshape(-1, 3)[:, 0]
        return [n for n, v in zip(self.joint_names, w) if v == 0.0]

    def body(self) -> Motion:
        """One frame of the model's mean pose (``reference``) on the skeleton it was trained on:
        what a motion of another skeleton is retargeted onto to be exaggerated (every joint
        rotates in its trained Euler order; the root and the hips also move)."""
        from ..motion import Skeleton
        from ..rotations.orders import order_name

        position = tuple(f"{axis}position" for axis in "XYZ")
        channels = tuple(
            (position if j in (0, self.hips) else ()) + tuple(f"{a}rotation" for a in order_name(order))
            for j, order in enumerate(self.orders)
        )
        skeleton = Skeleton(self.joint_names, self.parents, self.offsets, channels)
        return Motion(skeleton, self.reference[None], self.offsets[None], 1 / 30)

    @cached_property
    def hinge_limits(self) -> HingeLimits:
        """The knee and elbow limits this model learnt: measured on every training cycle it holds
        (each person's rotations rebuilt from their DOFs) on its own skeleton. Computed once a
        model (a model is not changed once trained)."""
        body = self.body()
        J = body.skeleton.n_joints
        people = self.cycle_performance[:, 0]
        rotations = np.concatenate(
            [
                dofs_to_rotations(
                    self.cycle_trajectories[people == p, :, : 3 * J].reshape(-1, 3 * J),
                    self.person_reference[p],
                    self.representation,
                    self.orders,
                )
                for p in np.unique(people)
            ]
        )
        translations = np.broadcast_to(body.translations[0], (len(rotations), J, 3))
        cycles = Motion(body.skeleton, rotations, translations, body.frame_time)
        return learn_hinge_limits([Take(cycles, self.skeleton_body)])

    @property
    def skeleton_body(self) -> Body:
        """The :class:`~expressive_mocap.body.Body` of the model's skeleton, read with the joint
        map the model records."""
        return Body.of(self.body().skeleton, self.joint_map or None)

    def dof_range(self, reference: str = "model") -> tuple[np.ndarray, np.ndarray]:
        """The lowest and highest value ``[D]`` of each DOF over every training sample, measured as
        :func:`~expressive_mocap.exaggeration.exaggerate` measures a motion with ``reference``: from
        the people's mean rotations (``"model"``: :attr:`lower`, :attr:`upper`) or each from its own
        mean (``"own"``)."""
        if reference == "own":
            return self.cycle_trajectories.min(axis=(0, 1)), self.cycle_trajectories.max(axis=(0, 1))
        return self.lower, self.upper

    @property
    def has_timing(self) -> bool:
        """Whether the model holds the timing features (models written before them do not)."""
        return self.cycle_timing is not None and self.timing_mappings is not None

    def timing_range(self) -> tuple[np.ndarray, np.ndarray]:
        """The lowest and highest value ``[2]`` of each timing feature over every training cycle."""
        assert self.cycle_timing is not None
        return self.cycle_timing.min(axis=0), self.cycle_timing.max(axis=0)

    def cycles_of(self, people: Sequence[int]) -> tuple[np.ndarray, np.ndarray]:
        """The training cycles of ``people`` (increasing indices), in the form
        :func:`~expressive_mocap.exaggeration.fit` takes for the trajectories
        ``self.trajectories[people]``: the people renumbered 0, 1, ..."""
        chosen_people = np.asarray(people, dtype=np.int64)
        chosen = np.isin(self.cycle_performance[:, 0], chosen_people)
        owners = self.cycle_performance[chosen].copy()
        owners[:, 0] = np.searchsorted(chosen_people, owners[:, 0])
        return self.cycle_trajectories[chosen], owners

    def compact(self, per_performance: int = COMPACT_CYCLES) -> ExaggerationModel:
        """This model keeping at most ``per_performance`` training cycles of each performance
        (evenly spread over them), as :meth:`save` with ``compact`` stores it."""
        chosen: list[int] = []
        owners = self.cycle_performance[:, 0] * len(self.levels) + self.cycle_performance[:, 1]
        for owner in np.unique(owners):
            rows = np.flatnonzero(owners == owner)
            spread = np.linspace(0, len(rows) - 1, min(per_performance, len(rows))).round().astype(int)
            chosen.extend(rows[np.unique(spread)].tolist())
        kept = np.array(sorted(chosen))
        timing = None if self.cycle_timing is None else self.cycle_timing[kept]
        return replace(
            self,
            cycle_trajectories=self.cycle_trajectories[kept],
            cycle_performance=self.cycle_performance[kept],
            cycle_timing=timing,
        )

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
        """``f(k) [..., D, r]``: the mapped coefficients at intensity ``k`` (scalar or array; a curved
        mapping continues along its tangent beyond the trained levels)."""
        return mapped(self.mappings, k, self.levels)

    def coefficient_spread(self) -> np.ndarray:
        """``[D, r]``: the mean square distance of the training performances' coefficients from the
        mapping at their own intensity (over people and intensities): what the mappings do not
        predict, the people's differences and the lines' misfit alike."""
        coefficients = np.einsum("tr,pktd->pkdr", self.basis, self.trajectories)
        return ((coefficients - self.predict_coefficients(self.levels)[None]) ** 2).mean(axis=(0, 1))

    def estimate(
        self, coefficients: np.ndarray, cycle_coefficients: np.ndarray | None = None, *, offsets: bool = False
    ) -> IntensityEstimate:
        """The current intensity of a motion from its coefficients ``[D, r]`` (the mean over its
        cycles): weighted least squares over the mapped coefficients of the key DOFs, each weighted
        by the inverse of its :meth:`coefficient_spread` (of the coefficients compared; a
        coefficient the mapping predicts well counts more; unweighted, the dataset-2 walks' own
        'normal' takes came out at 1.43 for 2).
        ``cycle_coefficients [C, D, r]`` (each cycle's) give the uncertainty its bootstrap part;
        see :class:`~expressive_mocap.exaggeration.IntensityEstimate`. ``offsets`` False (the
        default): only how each DOF varies over the cycle counts, not its mean (the direction a
        constant trajectory has in the basis is projected out of every coefficient compared), so
        a constant added to a DOF, an actor's own posture, cannot move the estimate."""
        return estimate_intensity(self, coefficients, cycle_coefficients, offsets=offsets)

    def estimate_intensity(self, coefficients: np.ndarray) -> float:
        """:meth:`estimate`'s intensity alone."""
        return self.estimate(coefficients).k

    def table(self, top: int | None = None) -> str:
        """The ranking as text: DOFs (most expressive first, key ones marked) then joints."""
        from .plot import ranking_table

        return ranking_table(self, top)

    def plot(self, path: str | os.PathLike, title: str = "") -> None:
        """A bar plot like the paper's Figure 1 (bottom): expressiveness per DOF, grouped by joint in
        skeleton order, key DOFs dark; below it the per-joint sums. PNG, written atomically."""
        from .plot import plot_ranking

        plot_ranking(self, path, title)

    def check_skeleton(self, motion: Motion) -> None:
        """Refuse (:class:`ModelError`) a motion whose skeleton is not the model's."""
        if motion.skeleton.names != self.joint_names:
            raise ModelError(
                f"the model was trained on a {len(self.joint_names)}-joint skeleton "
                f"({', '.join(self.joint_names[:3])}, ...); "
                f"the motion has {motion.skeleton.n_joints} joints ({', '.join(motion.skeleton.names[:3])}, ...)"
            )

    # ------------------------------------------------------------ files

    def to_bytes(self, compact: bool = False) -> bytes:
        """The file's bytes; ``compact``: :meth:`compact` first, and :data:`COMPACT_ARRAYS` in half
        precision (read back as float64)."""
        if compact:
            return self.compact()._to_bytes(np.float16)
        return self._to_bytes(np.float64)

    def _to_bytes(self, dtype) -> bytes:
        meta = {
            "format": FORMAT,
            "version": VERSION,
            "joint_names": list(self.joint_names),
            "dof_names": list(self.dof_names),
            "height": self.height,
            "hips": self.hips,
            "representation": self.representation,
            "energy": self.energy,
            "settings": self.settings.to_dict(),
            "joint_map": self.joint_map,
        }
        arrays = {name: np.asarray(getattr(self, name)) for name in ARRAYS}
        for name in COMPACT_ARRAYS:
            arrays[name] = arrays[name].astype(dtype)
        if self.has_timing:
            arrays.update({name: np.asarray(getattr(self, name)) for name in TIMING_ARRAYS})
        buffer = io.BytesIO()
        np.savez_compressed(buffer, meta=np.array(json.dumps(meta)), **arrays)
        return buffer.getvalue()

    def save(self, path: str | os.PathLike, compact: bool = False) -> None:
        """Write the model as ``.npz`` (plain arrays + one JSON string), atomically (``compact``:
        see :meth:`to_bytes`)."""
        atomic_write(path, self.to_bytes(compact))

    @classmethod
    def load(cls, source: str | os.PathLike | bytes) -> ExaggerationModel:
        """Read a model file written by :meth:`save` (``allow_pickle=False``; every array's shape is
        checked against the metadata, with a one-line :class:`ModelError` naming what is wrong)."""
        try:
            arrays, meta, name = read_model_file(source, "exaggeration model")
            if meta.get("format") != FORMAT or meta.get("version") != VERSION:
                raise ModelError(f"{name}: not an expressive-mocap exaggeration model of version {VERSION}")
            check_keys(arrays, ARRAYS + TIMING_ARRAYS, name)
            return cls._from_checked(arrays, meta, name)
        except ModelError:
            raise
        except MocapError as error:  # the file checks of files.py: a model file's problem all the same
            raise ModelError(str(error)) from None

    @classmethod
    def _from_checked(cls, arrays: dict[str, np.ndarray], meta: dict[str, Any], name: str) -> ExaggerationModel:
        try:
            _check_metadata(meta, name)
            _check_arrays(arrays, meta, name)
            model = cls(
                joint_names=tuple(meta["joint_names"]), dof_names=tuple(meta["dof_names"]),
                height=float(meta["height"]),
                hips=int(meta["hips"]), representation=meta["representation"], energy=float(meta["energy"]),
                settings=_settings(meta, name), joint_map=dict(meta.get("joint_map") or {}),
                **{k: _as_stored(k, arrays[k]) for k in ARRAYS},
                **{k: arrays[k] for k in TIMING_ARRAYS if k in arrays},
            )  # fmt: skip
            _check_model(model, name)
            return model
        except KeyError as error:
            raise ModelError(f"{name}: model file lacks {error}") from None
        except MocapError:
            raise
        except (TypeError, ValueError) as error:  # metadata of the wrong types, e.g. "height": "tall"
            raise ModelError(f"{name}: invalid metadata ({type(error).__name__}: {error})") from None


def _as_stored(key: str, values: np.ndarray) -> np.ndarray:
    """A file's array as the model holds it: flags as booleans, half precision read as float64."""
    if key in ("key", "person_key"):
        return values.astype(bool)
    return values.astype(np.float64) if values.dtype == np.float16 else values


def _check_metadata(meta: dict[str, Any], name: str) -> None:
    for key in ("joint_names", "dof_names"):
        if not isinstance(meta[key], list) or not all(isinstance(n, str) for n in meta[key]):
            raise ModelError(f"{name}: the metadata's {key} must be a list of names")
    if not isinstance(meta.get("settings", {}), dict):
        raise ModelError(f"{name}: the metadata's settings must be a JSON object")


def _settings(meta: dict[str, Any], name: str) -> TrainSettings:
    """The metadata's settings as a record, with the model's representation (an older file's
    missing entries take the defaults and are not written back; unknown ones are kept)."""
    try:
        return TrainSettings.from_dict(dict(meta.get("settings", {}), representation=meta["representation"]))
    except ArgumentError as error:
        raise ModelError(f"{name}: the metadata's {error}") from None


def _check_model(model: ExaggerationModel, name: str) -> None:
    """What the arrays' shapes cannot tell: an actor of some height, two intensities at least, a
    joint map that is one body on the model's own skeleton (it is how other skeletons reach it)."""
    if not (np.isfinite(model.height) and model.height > 0):
        raise ModelError(f"{name}: the actor's height must be a positive length, got {model.height!r}")
    if len(np.unique(model.levels)) < 2:
        raise ModelError(
            f"{name}: the levels must hold two different intensities at least, got {model.levels.tolist()}"
        )
    if model.joint_map:
        try:
            _ = model.skeleton_body.joint_map
        except MocapError as error:
            raise ModelError(f"{name}: its joint map does not fit its own skeleton: {error}") from None


def _check_arrays(arrays: dict[str, np.ndarray], meta: dict[str, Any], name: str) -> None:
    """Every array of the right shape for the metadata and the others, the skeleton a tree."""
    J, D = len(meta["joint_names"]), len(meta["dof_names"])
    for key, ndim in (("basis", 2), ("trajectories", 4), ("mappings", 3), ("cycle_trajectories", 3)):
        if finite_array(arrays, key, name, kinds="f").ndim != ndim:
            raise ModelError(f"{name}: {key!r} has shape {list(arrays[key].shape)}, expected {ndim} dimensions")
    T, r = arrays["basis"].shape
    P, K = arrays["trajectories"].shape[:2]
    degree = arrays["mappings"].shape[-1]
    N = arrays["cycle_trajectories"].shape[0]
    shapes = {
        "parents": (J,), "offsets": (J, 3), "orders": (J, 3), "weights": (D,), "levels": (K,), "basis": (T, r),
        "singular_values": (r,), "expressiveness": (P, D), "overall": (D,), "key": (D,), "person_key": (P, D),
        "mappings": (D, r, degree), "reference": (J, 4), "person_reference": (P, J, 4), "lower": (D,), "upper": (D,),
        "trajectories": (P, K, T, D), "cycle_trajectories": (N, T, D), "cycle_performance": (N, 2),
    }  # fmt: skip
    for key, shape in shapes.items():
        finite_array(arrays, key, name, shape, kinds="fiub")
    if any(key in arrays for key in TIMING_ARRAYS):
        timing_shapes = {"cycle_timing": (N, 2), "timing_mappings": (2, K), "timing_predictability": (2,)}
        for key, shape in timing_shapes.items():
            finite_array(arrays, key, name, shape, kinds="f")
    owners = arrays["cycle_performance"]
    valid = owners.dtype.kind in "iu" and ((owners >= 0) & (owners < [P, K])).all()
    if not valid or len(np.unique(owners[:, 0] * K + owners[:, 1])) != P * K:
        raise ModelError(
            f"{name}: 'cycle_performance' must give every cycle a person < {P} and an intensity index < {K}, "
            "and every performance a cycle"
        )
    representation = meta["representation"]
    if D != 3 * J + 1 or not isinstance(representation, str) or representation not in REPRESENTATIONS:
        raise ModelError(f"{name}: {D} DOFs for {J} joints in representation {representation!r}")
    parents, orders = arrays["parents"].tolist(), arrays["orders"].tolist()
    tree = all(p == -1 if j == 0 else p in range(j) for j, p in enumerate(parents))
    if not tree or any(sorted(o) != [0, 1, 2] for o in orders) or int(meta["hips"]) not in range(J):
        raise ModelError(
            f"{name}: the skeleton is inconsistent (parents must each come before their joint, orders be axis "
            "permutations, hips a joint)"
        )


__all__ = ["ARRAYS", "COMPACT_ARRAYS", "COMPACT_CYCLES", "FORMAT", "TIMING_ARRAYS", "VERSION", "ExaggerationModel"]
