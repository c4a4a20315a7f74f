"""The body-mechanics model: from a frame's dynamic features to the pose a neutral performer
would have (the decoupling method of Boehs et al.), and its file format.

A model predicts the local rotations of every joint except the root and the hips (those come
from the motion itself), each on the hemisphere of its mean training rotation. It knows the
skeleton it was trained on (joint names), the features' normalisation, the settings and the
mean squared errors of every training stage, the range of features it was trained on (inputs
are clipped into it: outside it the network extrapolates, e.g. to a jump or a sprint it never
saw), and optionally a calibration to one actor or capture session (per joint a constant
rotation, and by default a threshold of activity above that session's neutral residue).

Model files are ``.npz`` archives of plain arrays plus one JSON string, read with
``allow_pickle=False``: data, never code.
"""

from __future__ import annotations

import io
import json
import os
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from importlib import resources

import numpy as np

from .._utils.files import atomic_write
from .._utils.model_files import check_keys, finite_array, read_model_file
from ..body.contacts import floor_of
from ..body.take import Take
from ..errors import ArgumentError, ModelError
from ..motion import Motion, Skeleton
from ..ops import Arms, Trunk
from ..rotations import quat
from .algebra import BODY_SMOOTHING
from .features import FEATURE_NAMES, dynamic_features
from .network import Mlp
from .pelvis import Pelvis, mean_posture, upright
from .records import BodyModelSettings, TrainingReport
from .trunk import trunk_threshold

FORMAT = "expressive-mocap body model"
VERSION = 1
DEFAULT_MODEL = "body_model.npz"  # shipped inside the package (python/expressive_mocap/data/)

# Calibration's activity threshold: the NEUTRAL_PERCENTILE-th percentile of a joint's expressive
# angle over the session's neutral clips is read as NEUTRAL_ANGLE degrees, to which the default
# activity index gives 0.2 (chosen on dataset-1's neutral locomotion, each clip left out in turn:
# experiments/SESSIONS.md).
NEUTRAL_PERCENTILE = 90.0
NEUTRAL_ANGLE = 20.0


@dataclass(frozen=True)
class BodyModel:
    """``network`` maps raw features ``[N, 19]`` (their z-scoring is folded into its first
    layer) to predicted rotations ``[N, 4 P]``.

    ``joint_names``: the skeleton the model was trained on; ``predicted``: indices of the
    predicted joints; ``hemispheres [P, 4]``: each predicted joint's mean training rotation;
    ``thigh_reference [2, 4]``: hemisphere of the thigh features; ``calibration [J, 4]`` or
    None: ``Q_j`` applied to the prediction as ``Q_j * B_j``; ``activity_scale [J]`` or None: per
    joint, the angle of the expressive component is divided by it before the activity index
    reads it (at least 1; set by calibration); ``feature_range [2, 19]`` or None:
    the lowest and highest feature values the network is trusted with (inputs are clipped into it);
    ``trunk`` or None: the trunk chain read as one, with its threshold; ``arms`` or None: the
    limbs filtered in world axes (:mod:`~expressive_mocap.decoupling.arms`); ``pelvis`` or None: the
    spine is predicted for the training clips' pelvis posture and carried onto the motion's
    (:mod:`~expressive_mocap.decoupling.trunk`, :mod:`~expressive_mocap.decoupling.pelvis`).
    ``settings`` and ``report``: what training was run with and how every stage scored
    (:class:`~expressive_mocap.decoupling.records.BodyModelSettings`,
    :class:`~expressive_mocap.decoupling.records.TrainingReport`; fields a file lacks are None).
    """

    joint_names: tuple[str, ...]
    predicted: np.ndarray
    hemispheres: np.ndarray
    thigh_reference: np.ndarray
    network: Mlp
    settings: BodyModelSettings = field(default_factory=BodyModelSettings)
    report: TrainingReport = field(default_factory=TrainingReport)
    calibration: np.ndarray | None = None
    feature_range: np.ndarray | None = None
    activity_scale: np.ndarray | None = None
    trunk: Trunk | None = None
    pelvis: Pelvis | None = None
    arms: Arms | None = None

    def __repr__(self) -> str:
        # One line: the dataclass default prints every weight.
        sizes = [self.network.layers[0].weights.shape[0]] + [layer.weights.shape[1] for layer in self.network.layers]
        mse = self.report.fine_tuned.test_mse if self.report.fine_tuned else None
        return (
            f"BodyModel({len(self.joint_names)}-joint skeleton (root {self.joint_names[0]!r}), "
            f"{len(self.predicted)} joints predicted, "
            f"network {'-'.join(map(str, sizes))}, test MSE {'?' if mse is None else f'{mse:.3g}'}"
            f"{', calibrated' if self.calibration is not None else ''})"
        )

    # ---------------------------------------------------------------- prediction

    def check_skeleton(self, motion: Motion | Skeleton) -> None:
        """Refuse a motion (or skeleton) of another skeleton, naming the difference."""
        names = (motion.skeleton if isinstance(motion, Motion) else motion).names
        if names != self.joint_names:
            missing = [n for n in self.joint_names if n not in names]
            extra = [n for n in names if n not in self.joint_names]
            detail = f"missing {', '.join(missing[:5])}" if missing else ""
            detail += ("; " if detail and extra else "") + (f"unknown {', '.join(extra[:5])}" if extra else "")
            raise ModelError(
                f"this body model was trained on a {len(self.joint_names)}-joint skeleton "
                f"({', '.join(self.joint_names[:4])}, ...); "
                f"the motion has {len(names)} joints{': ' + detail if detail else ' in another order'}"
            )

    def features(self, motion: Motion | Take, floor: float | None = None) -> np.ndarray:
        """The model's inputs ``[F, 19]`` for ``motion`` (or a take of it): causal dynamic
        features (floor: the clip's 5th percentile of toe heights unless given)."""
        take = Take.of(motion)
        self.check_skeleton(take.motion)
        return model_features(take, self.thigh_reference, floor)

    def predict(self, motion: Motion | Take, floor: float | None = None) -> np.ndarray:
        """Body-mechanics local rotations ``[F, J, 4]``: the network's pose for each frame's
        features (calibrated if the model is), root and hips copied from ``motion``."""
        take = Take.of(motion)
        return self.predict_from_features(take.motion.rotations, self.features(take, floor))

    def predict_take(self, take: Take) -> np.ndarray:
        """:meth:`predict` of a take (what :func:`~expressive_mocap.decoupling.decompose` calls)."""
        return self.predict(take)

    def predict_from_features(
        self, rotations: np.ndarray, features: np.ndarray, posture: np.ndarray | None = None
    ) -> np.ndarray:
        """As :meth:`predict`, from ``features [F, 19]`` and the motion's ``rotations [F, J, 4]``.
        ``posture``: the pelvis posture the spine is carried onto, ``[4]`` or per frame ``[F, 4]``
        (None: the mean of ``rotations``' frames, one clip's; see :mod:`.pelvis`)."""
        if self.feature_range is not None:
            low, high = self.feature_range.astype(features.dtype)
            features = np.clip(features, low, high)
        out = self.network.forward(features).reshape(len(features), len(self.predicted), 4)
        body = np.array(rotations, dtype=np.float64, copy=True)
        body[:, _as_slice(self.predicted)] = quat.normalize(out)
        if self.pelvis is not None:
            held = mean_posture(rotations, self.pelvis.path) if posture is None else np.asarray(posture)
            c = upright(held, self.pelvis)
            body[:, self.pelvis.spine] = quat.mul(c if c.ndim == 2 else c[None], body[:, self.pelvis.spine])
        if self.calibration is not None:
            body = quat.mul(self.calibration[None], body)
        return body

    # ---------------------------------------------------------------- calibration

    def calibrated(self, neutral: Sequence[Motion], threshold: bool = True) -> BodyModel:
        """This model calibrated to the actor or session of ``neutral`` clips (neutral movement
        of that session): per joint ``Q_j`` = mean over all frames of ``O_j * B_j^-1``. With
        ``threshold`` also each joint's activity threshold: what calibration leaves of the
        neutral clips' expressive angle (its NEUTRAL_PERCENTILE-th percentile over their frames)
        is read as NEUTRAL_ANGLE degrees, little activity; ``activity_scale`` = the larger of 1
        and that angle / NEUTRAL_ANGLE, so joints the model already fits keep the default; and
        the trunk chain's, its lean read by the same rule (never below the model's own)."""
        if not neutral:
            raise ArgumentError("calibration needs at least one neutral clip")
        model = replace(self, calibration=None, activity_scale=None)
        original = np.concatenate([m.rotations for m in neutral])
        per_clip = [model.predict(m) for m in neutral]
        predicted = np.concatenate(per_clip)
        q = quat.mean_rotation(quat.mul(original, quat.conjugate(predicted)))
        q[[j for j in range(len(self.joint_names)) if j not in set(self.predicted.tolist())]] = [0.0, 0.0, 0.0, 1.0]
        model = replace(model, calibration=q)
        if threshold:
            residue = quat.angle(quat.mul(original, quat.conjugate(quat.mul(q[None], predicted))))
            angle = np.degrees(np.percentile(residue, NEUTRAL_PERCENTILE, axis=0))
            scale = np.maximum(1.0, angle / NEUTRAL_ANGLE)
            calibrated = [quat.mul(q[None], p) for p in per_clip]  # what the calibrated model predicts
            model = replace(model, activity_scale=scale, trunk=self._session_trunk(neutral, calibrated))
        return model

    def _session_trunk(self, neutral: Sequence[Motion], predictions: Sequence[np.ndarray]) -> Trunk | None:
        """The trunk's threshold for a session: the lean the calibrated model's ``predictions``
        leave on its ``neutral`` clips, read as each joint's residue is, never below this model's own."""
        if self.trunk is None:
            return None
        chain = (self.trunk.joints, self.trunk.bones)
        sigmas = [BODY_SMOOTHING * m.fps for m in neutral]
        originals = [m.rotations for m in neutral]
        session = trunk_threshold(chain, originals, predictions, sigmas, NEUTRAL_PERCENTILE, NEUTRAL_ANGLE)
        return session if session.scale > self.trunk.scale else self.trunk

    def calibration_angles(self) -> dict[str, float]:
        """Degrees of each joint's calibration rotation (empty when uncalibrated)."""
        if self.calibration is None:
            return {}
        return {n: float(np.degrees(a)) for n, a in zip(self.joint_names, quat.angle(self.calibration))}

    # ---------------------------------------------------------------- files

    def to_bytes(self) -> bytes:
        meta = {
            "format": FORMAT,
            "version": VERSION,
            "joint_names": list(self.joint_names),
            "feature_names": list(FEATURE_NAMES),
            "settings": self.settings.to_json(),
            "report": self.report.to_json(),
        }
        arrays = {
            "meta": np.array(json.dumps(meta)),
            "predicted": self.predicted.astype(np.int64),
            "hemispheres": self.hemispheres,
            "thigh_reference": self.thigh_reference,
            **self.network.to_arrays("network"),
        }
        if self.calibration is not None:
            arrays["calibration"] = self.calibration
        if self.feature_range is not None:
            arrays["feature_range"] = self.feature_range
        if self.activity_scale is not None:
            arrays["activity_scale"] = self.activity_scale
        if self.pelvis is not None:
            arrays["pelvis_path"] = np.array(self.pelvis.path, dtype=np.int64)
            arrays["pelvis_spine"] = np.array(self.pelvis.spine, dtype=np.int64)
            arrays["pelvis_reference"] = self.pelvis.reference
        if self.trunk is not None:
            arrays["trunk_joints"] = np.array(self.trunk.joints, dtype=np.int64)
            arrays["trunk_bones"] = np.array(self.trunk.bones, dtype=np.float64)
            arrays["trunk_scale"] = np.array(self.trunk.scale, dtype=np.float64)
        if self.arms is not None:
            arrays["arm_parents"] = np.array(self.arms.parents, dtype=np.int64)
            arrays["arm_joints"] = np.array(self.arms.limbs, dtype=np.int64)
        buffer = io.BytesIO()
        np.savez_compressed(buffer, **arrays)
        return buffer.getvalue()

    def save(self, path: str | os.PathLike) -> None:
        """Write the model as an .npz file, atomically."""
        atomic_write(path, self.to_bytes())

    @classmethod
    def load(cls, source: str | os.PathLike | bytes | None = None) -> BodyModel:
        """Read a model file (default: the model shipped with the package). Arrays only, no
        pickles; the contents are checked against the format, with a clear error otherwise."""
        if source is None:
            arrays, meta, _ = read_model_file(shipped_model_bytes(), "model file")
            return cls._from_arrays(arrays, meta, f"the shipped {DEFAULT_MODEL}")
        arrays, meta, name = read_model_file(source, "model file")
        model = cls._from_arrays(arrays, meta, name)
        problem = poor_fit(model.report)
        if problem:  # loading it is allowed (to inspect it), but its results mean little
            warnings.warn(f"{name}: a poor model: {problem}; its decompositions are unreliable", stacklevel=2)
        return model

    @classmethod
    def _from_arrays(cls, arrays: dict, meta: dict, name: str) -> BodyModel:
        # One check after another, each naming what is wrong in the file: longer than 60 lines,
        # kept in one piece so the whole format is read in one place.
        if meta.get("format") != FORMAT or meta.get("version") != VERSION:
            raise ModelError(
                f"{name}: not an expressive-mocap body model of version {VERSION} "
                f"(format {meta.get('format')!r}, version {meta.get('version')!r})"
            )
        if meta.get("feature_names") != list(FEATURE_NAMES):
            raise ModelError(
                f"{name}: the model's features {meta.get('feature_names')} are not this version's {list(FEATURE_NAMES)}"
            )
        joint_names = meta.get("joint_names")
        if (
            not isinstance(joint_names, list)
            or not joint_names
            or not all(isinstance(n, str) for n in joint_names)
            or len(set(joint_names)) != len(joint_names)
        ):
            raise ModelError(f"{name}: the metadata's joint_names must be a list of distinct joint names")
        settings = BodyModelSettings.from_json(meta.get("settings", {}), f"{name}: the metadata's settings")
        report = TrainingReport.from_json(meta.get("report", {}), f"{name}: the metadata's report")
        predicted = finite_array(arrays, "predicted", name, kinds="iu")
        if (
            predicted.ndim != 1
            or len(predicted) == 0
            or predicted.min() < 0
            or predicted.max() >= len(joint_names)
            or len(set(predicted.tolist())) != len(predicted)
        ):
            raise ModelError(
                f"{name}: predicted joint indices must be distinct indices of the {len(joint_names)} joints"
            )
        for key in arrays:
            if key.startswith("network.") and not key.endswith(".activations"):
                finite_array(arrays, key, name, kinds="f")  # weights and biases: finite floats
        try:
            network = Mlp.from_arrays(arrays, "network")
        except (KeyError, ValueError) as error:
            raise ModelError(f"{name}: the network's arrays are invalid ({error})") from None
        layers = [f"network.{i}.{part}" for i in range(len(network.layers)) for part in ("weights", "bias")]
        check_keys(
            arrays,
            [
                "predicted",
                "hemispheres",
                "thigh_reference",
                "calibration",
                "feature_range",
                "activity_scale",
                "trunk_joints",
                "trunk_bones",
                "trunk_scale",
                "arm_parents",
                "arm_joints",
                "pelvis_path",
                "pelvis_spine",
                "pelvis_reference",
                "network.activations",
                *layers,
            ],
            name,
        )
        n_features = len(FEATURE_NAMES)
        if network.n_inputs != n_features or network.n_outputs != 4 * len(predicted):
            raise ModelError(
                f"{name}: the network maps {network.n_inputs} -> {network.n_outputs}, "
                f"expected {n_features} -> {4 * len(predicted)}"
            )
        return cls(
            joint_names=tuple(joint_names),
            predicted=predicted.astype(np.int64),
            hemispheres=finite_array(arrays, "hemispheres", name, (len(predicted), 4), kinds="f"),
            thigh_reference=finite_array(arrays, "thigh_reference", name, (2, 4), kinds="f"),
            network=network,
            settings=settings,
            report=report,
            calibration=finite_array(arrays, "calibration", name, (len(joint_names), 4), kinds="f")
            if "calibration" in arrays
            else None,
            feature_range=_feature_range(arrays, name),
            activity_scale=_activity_scale(arrays, name, len(joint_names)),
            trunk=_trunk(arrays, name, predicted),
            pelvis=_pelvis(arrays, name, predicted, len(joint_names)),
            arms=_arms(arrays, name, predicted, len(joint_names)),
        )


def _feature_range(arrays: dict, name: str) -> np.ndarray | None:
    if "feature_range" not in arrays:
        return None  # a model file from before feature ranges: inputs go to the network unclipped
    values = finite_array(arrays, "feature_range", name, (2, len(FEATURE_NAMES)), kinds="f")
    if np.any(values[0] > values[1]):
        raise ModelError(f"{name}: feature_range must hold the lowest values (row 0) and the highest (row 1)")
    return values


def _activity_scale(arrays: dict, name: str, n_joints: int) -> np.ndarray | None:
    if "activity_scale" not in arrays:
        return None
    values = finite_array(arrays, "activity_scale", name, (n_joints,), kinds="f")
    if np.any(values < 1.0):
        raise ModelError(f"{name}: activity_scale must be at least 1 for every joint")
    return values


def _trunk(arrays: dict, name: str, predicted: np.ndarray) -> Trunk | None:
    keys = ("trunk_joints", "trunk_bones", "trunk_scale")
    if not any(k in arrays for k in keys):
        return None  # a model file from before the trunk was read as a chain
    joints = finite_array(arrays, "trunk_joints", name, kinds="iu")
    if joints.ndim != 1 or not len(joints) or not set(joints.tolist()) <= set(predicted.tolist()):
        raise ModelError(f"{name}: trunk_joints must be a list of predicted joints")
    bones = finite_array(arrays, "trunk_bones", name, (len(joints), 3), kinds="f")
    scale = float(finite_array(arrays, "trunk_scale", name, (), kinds="f"))
    if np.linalg.norm(bones.sum(axis=0)) <= 1e-9 or scale <= 0:
        raise ModelError(f"{name}: trunk_bones must make a trunk of some length and trunk_scale be a positive number")
    carried = tuple((float(x), float(y), float(z)) for x, y, z in bones)
    return Trunk(tuple(int(j) for j in joints), carried, scale)


def _arms(arrays: dict, name: str, predicted: np.ndarray, n_joints: int) -> Arms | None:
    if "arm_parents" not in arrays and "arm_joints" not in arrays:
        return None  # a model file from before the arms were filtered in world axes
    parents = finite_array(arrays, "arm_parents", name, (n_joints,), kinds="iu").tolist()
    limbs = finite_array(arrays, "arm_joints", name, kinds="iu")
    if parents[0] != -1 or not all(0 <= p < j for j, p in enumerate(parents) if j):
        raise ModelError(
            f"{name}: arm_parents must be the skeleton's parents, the root's -1 first, each before its child"
        )
    if limbs.ndim != 1 or not len(limbs) or not set(limbs.tolist()) <= set(predicted.tolist()):
        raise ModelError(f"{name}: arm_joints must be a list of predicted joints")
    return Arms(tuple(int(p) for p in parents), tuple(int(j) for j in limbs))


def _pelvis(arrays: dict, name: str, predicted: np.ndarray, n_joints: int) -> Pelvis | None:
    keys = ("pelvis_path", "pelvis_spine", "pelvis_reference")
    if not any(k in arrays for k in keys):
        return None  # a model file from before the spine was predicted for a reference pelvis
    path = finite_array(arrays, "pelvis_path", name, kinds="iu")
    spine = int(finite_array(arrays, "pelvis_spine", name, (), kinds="iu"))
    reference = finite_array(arrays, "pelvis_reference", name, (4,), kinds="f")
    if path.ndim != 1 or not len(path) or path.min() < 0 or path.max() >= n_joints or path[0] != 0:
        raise ModelError(f"{name}: pelvis_path must list joints from the root (0) to the hips")
    if spine not in set(predicted.tolist()) or abs(np.linalg.norm(reference) - 1.0) > 1e-6:
        raise ModelError(f"{name}: pelvis_spine must be a predicted joint and pelvis_reference a unit quaternion")
    return Pelvis(tuple(int(j) for j in path), spine, reference)


def poor_fit(report: TrainingReport) -> str | None:
    """Why a trained body-mechanics model is of no use, or None: its network must predict the
    held-out clips' poses better than their mean training pose does (a network trained on too
    few clips, or for too few iterations, may not). None too when the report cannot tell."""
    final = report.fine_tuned.test_mse if report.fine_tuned else None
    baseline = report.mean_pose.test_mse if report.mean_pose else None
    if final is None or baseline is None or final < baseline:
        return None
    explained = report.fine_tuned.test_variance_explained if report.fine_tuned else None
    return f"its held-out pose error {final:.3g} is no better than the mean training pose's {baseline:.3g}" + (
        f" (test variance explained {explained:.2f})" if explained is not None else ""
    )


def shipped_model_bytes() -> bytes:
    """The bytes of the model shipped inside the package."""
    path = resources.files("expressive_mocap") / "data" / DEFAULT_MODEL
    if not path.is_file():
        raise ModelError(f"the package has no shipped model ({DEFAULT_MODEL}); train one with `expressive-mocap train`")
    return path.read_bytes()


def pose_vectors(rotations: np.ndarray, predicted: np.ndarray, hemispheres: np.ndarray) -> np.ndarray:
    """Flattened poses ``[F, 4 P]``: the predicted joints' rotations on their reference hemispheres."""
    q = rotations[:, predicted]
    q = np.where(np.sum(q * hemispheres[None], axis=-1, keepdims=True) < 0, -q, q)
    return q.reshape(len(rotations), -1)


def model_features(motion: Motion | Take, thigh_reference: np.ndarray, floor: float | None = None) -> np.ndarray:
    """The 19 causal dynamic features ``[F, 19]`` as a model sees them (training and prediction
    alike): on the clip's own floor unless ``floor`` is given."""
    take = Take.of(motion)
    return dynamic_features(
        take, floor=floor_of(take) if floor is None else floor, thigh_reference=thigh_reference, causal=True
    )


def _as_slice(indices: np.ndarray) -> slice | np.ndarray:
    """``indices`` as a slice where they run in steps of one (the shipped model's do): writing
    through a slice is ten times faster than through an index array, on a whole batch of frames."""
    if len(indices) and np.array_equal(indices, np.arange(indices[0], indices[0] + len(indices))):
        return slice(int(indices[0]), int(indices[0]) + len(indices))
    return indices


__all__ = [
    "DEFAULT_MODEL",
    "FORMAT",
    "VERSION",
    "BodyModel",
    "model_features",
    "poor_fit",
    "pose_vectors",
    "shipped_model_bytes",
]
