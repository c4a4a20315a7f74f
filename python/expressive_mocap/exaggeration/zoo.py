"""The exaggeration models shipped with the package: one per action of the Bandai-Namco
dataset-2 and style axis, each trained on the first takes of three styles along the axis (the
rest held out), chosen for a motion by how well each fits it.

The fit (the intensity estimate's residual) reads how each joint varies over a cycle, heading
removed: a straight walk fits a turning walk's model about as well as its own (and a run's), and a
wave of the left hand the model of both hands'. So a model is only a candidate for a motion whose
:func:`signature` (how fast it travels and turns, which hand moves) lies within what its training clips show
(:data:`SIGNATURE_MARGINS` wider); among candidates, the best fit wins. The index lists every
model the recipe makes with its validation; only those that passed it ship.

The recipe is here (:data:`ACTIONS`, :data:`AXES`, :func:`build`), so that
``benches/build_models.py`` rebuilds every shipped file and a test can check one; the files, their
index (what each was trained on, its validation) and card are in ``expressive_mocap/data/exaggeration/``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

from ..body.contacts import foot_contacts
from ..body.take import Take
from ..errors import ArgumentError, MocapError
from ..motion import Motion
from ..reference.features import heading_yaw
from .cycles import cycles_for
from .edit import current_intensity
from .estimate import IntensityEstimate
from .gestures import repetition
from .model import ExaggerationModel

ACTIONS = (
    "walk",
    "walk-turn-left",
    "walk-turn-right",
    "run",
    "raise-up-left-hand",
    "raise-up-right-hand",
    "raise-up-both-hands",
    "wave-left-hand",
    "wave-right-hand",
    "wave-both-hands",
)
LOCOMOTION = ("walk", "walk-turn-left", "walk-turn-right", "run")  # gait cycles; the arm actions: the whole clip
AXES = {  # styles at intensities 1, 2, 3 (every model of both is validated; those that pass ship)
    "energy": ("exhausted", "normal", "active"),
    "age": ("elderly", "normal", "youthful"),
    "masculinity": ("feminine", "normal", "masculine"),
}
PEOPLE = tuple(range(1, 9))  # takes 1-8 of each style, as eight people; the later takes are held out
# The mappings' degree: a parabola through the three styles' coefficients, not a line. The styles
# are not evenly spaced (the exhausted walk is not less of the active one), and a line through
# all three moved held-out normal walks taken to 3 less than halfway to the active ones.
DEGREE = 2
INDEX = "index.json"
# How far beyond its training clips' range a motion's signature may lie for a model to be a candidate.
# Speed: actor heights per second; turn: degrees per second; left hand: share of the hands' motion;
# flight: share of frames; repeats: an autocorrelation (a raise reads 0-0.02, a wave 0.4 or more).
SIGNATURE_MARGINS = {"speed": 0.1, "turn": 5.0, "left_hand": 0.1, "flight": 0.02, "repeats": 0.2}
# The fit residual above which a motion the signature admits is still refused: the walks model
# (parabolic mappings) reads held-out walks of its own session at 0.5-0.8, another session's at
# 1.4-6.4 (median 2.7; its slowest and stiffest styles highest), a run at 5.1-5.9 and a wave at
# 6.4-6.7 (the estimate warns from 2, POOR_FIT).
CHOICE_FIT = 4.0


@dataclass(frozen=True)
class ShippedModel:
    """One shipped model: its ``action`` and ``axis`` (``styles`` at intensities 1, 2, 3), its
    file, and what the index says of it (training takes, signature, held-out figures)."""

    action: str
    axis: str
    styles: tuple[str, ...]
    file: str
    record: dict[str, Any]

    @property
    def name(self) -> str:
        return f"{self.action} ({self.axis})"

    def load(self) -> ExaggerationModel:
        """The model (read once a process: choosing one loads every candidate)."""
        return _load(self.file)

    def admits(self, found: dict[str, float]) -> bool:
        """Whether a motion of :func:`signature` ``found`` could be this model's action."""
        ranges = self.record.get("signature", {})
        return all(
            low - SIGNATURE_MARGINS[key] <= found[key] <= high + SIGNATURE_MARGINS[key]
            for key, (low, high) in ranges.items()
            # A walk's hands need not repeat their swing (a sad or stiff-armed walk's barely do):
            # repeated strokes tell a wave from a raise, not a walk from anything.
            if not (key == "repeats" and self.action in LOCOMOTION)
        )


def _folder():
    return resources.files("expressive_mocap") / "data" / "exaggeration"


@cache
def _load(file: str) -> ExaggerationModel:
    return ExaggerationModel.load(_folder().joinpath(file).read_bytes())


def index_records() -> list[dict[str, Any]]:
    """Every model the recipe makes, shipped or not, with its validation (the index's records)."""
    index = _folder() / INDEX
    return json.loads(index.read_text()) if index.is_file() else []


def shipped_models() -> list[ShippedModel]:
    """The shipped models, in the index's order (empty when the package holds none)."""
    return [
        ShippedModel(r["action"], r["axis"], tuple(r["styles"]), r["file"], r) for r in index_records() if r["shipped"]
    ]


def candidates(action: str | None = None, axis: str | None = None) -> list[ShippedModel]:
    """The shipped models of ``action`` and ``axis`` (None: any), or an :class:`ArgumentError`
    listing what there is."""
    models = shipped_models()
    chosen = [m for m in models if action in (None, m.action) and axis in (None, m.axis)]
    if not chosen:
        have = ", ".join(dict.fromkeys(m.action for m in models)) or "none"
        axes = ", ".join(dict.fromkeys(m.axis for m in models)) or "none"
        raise ArgumentError(
            f"no shipped model of action {action or 'any'} along axis {axis or 'any'} (actions: {have}; axes: {axes})"
        )
    return chosen


def signature(motion: Motion | Take) -> dict[str, float]:
    """What tells actions apart that the fit does not see: ``speed``, the hips' horizontal path
    per second in actor heights; ``turn``, the heading's change per second (degrees, left
    positive; from the line between the upper legs); ``left_hand``, the left hand's share of both
    hands' paths about their shoulders (0.5: both alike); ``flight``, the share of frames with
    neither foot on the ground (a run's); ``repeats``, how well the moving hand's strokes repeat
    (:func:`~expressive_mocap.exaggeration.gestures.repetition`: a wave's, not a raise's)."""
    take = Take.of(motion)
    roles, (_, positions) = take.body.roles, take.fk
    seconds = max(take.motion.duration, 1e-9)
    travel = np.linalg.norm(np.diff(positions[:, roles.hips][:, [0, 2]], axis=0), axis=1).sum()
    yaw = np.unwrap(heading_yaw(positions[:, roles.upper_legs[0]], positions[:, roles.upper_legs[1]]))
    jmap = take.body.joint_map
    paths = []
    for hand, shoulder in (("left_hand", "left_upper_arm"), ("right_hand", "right_upper_arm")):
        about = positions[:, jmap[hand]] - positions[:, jmap[shoulder]]
        paths.append(float(np.linalg.norm(np.diff(about, axis=0), axis=1).sum()))
    total = sum(paths)
    return {
        "speed": float(travel / seconds / take.body.actor_height),
        "turn": float(np.degrees(yaw[-1] - yaw[0]) / seconds),
        "left_hand": paths[0] / total if total > 0 else 0.5,
        "flight": float(np.mean(~foot_contacts(take).any(axis=1))),
        "repeats": repetition(take),
    }


def fit(model: ExaggerationModel, motion: Motion | Take) -> IntensityEstimate:
    """How ``motion`` (on the model's skeleton) fits ``model``: its intensity estimate, measured
    over the cycles the model was trained on (gait cycles, or a gesture's strokes or span; a clip
    with no gait cycle is read whole, and then fits a gait model poorly)."""
    take = Take.of(motion)
    return current_intensity(model, take, cycles_for(take, model.settings.cycle, model.settings.foot))


def choose(
    motion: Motion | Take, models: list[ShippedModel], explicit: bool = False
) -> tuple[ShippedModel, ExaggerationModel, list[tuple[ShippedModel, float]]]:
    """The model among ``models`` that fits ``motion`` best (lowest residual) of those whose
    action it could be (:meth:`ShippedModel.admits`; all of them when the caller named the action:
    ``explicit``), loaded, with every candidate's residual (best first); a :class:`MocapError`
    listing every model's residual when none fits (none admits the motion, or the best residual is
    above :data:`CHOICE_FIT`)."""
    found = signature(motion)
    fits = []
    for shipped in models:
        model = shipped.load()
        fits.append((fit(model, motion).residual, shipped, model))
    fits.sort(key=lambda f: f[0])
    ranked = [(s, r) for r, s, _ in fits]
    admitted = [f for f in fits if explicit or f[1].admits(found)]
    if not admitted or admitted[0][0] > CHOICE_FIT:
        listed = ", ".join(f"{s.name} {r:.2f}{'' if s.admits(found) else ' (not its action)'}" for s, r in ranked)
        moves = ", ".join(f"{key} {value:.2f}" for key, value in found.items())
        # Named, the action was the user's: only a model of their own is left to suggest.
        hint = "" if explicit else "name its --action, or "
        raise MocapError(
            f"no shipped model fits this motion ({moves}; fit residuals, about 1 for a motion like the training "
            f"takes, above {CHOICE_FIT:g} refused: {listed}); {hint}pass --model with a model of your own"
        )
    _, shipped, model = admitted[0]
    return shipped, model, ranked


def training_clips(dataset: str | Path, action: str, axis: str) -> list[list[Motion]]:
    """The clips a shipped model of ``action`` along ``axis`` learns from, as its people (each
    person's three styles in the axis' order), read from the unpacked dataset-2 folder ``dataset``."""
    from ..bvh.reader import read_bvh

    if action not in ACTIONS or axis not in AXES:
        raise ArgumentError(
            f"unknown action {action!r} or axis {axis!r} (actions: {', '.join(ACTIONS)}; axes: {', '.join(AXES)})"
        )
    folder = Path(dataset)
    return [[read_bvh(folder / f"dataset-2_{action}_{style}_{p:03d}.bvh") for style in AXES[axis]] for p in PEOPLE]


def build(clips: list[list[Motion]], action: str) -> ExaggerationModel:
    """The shipped model of ``action`` from its :func:`training_clips`, trained as the package's
    was (what ``benches/build_models.py`` runs)."""
    from .training import train

    return train(clips, (1.0, 2.0, 3.0), cycle="all" if action in LOCOMOTION else "whole", degree=DEGREE)


def signature_ranges(clips: list[list[Motion]]) -> dict[str, list[float]]:
    """The range of a model's training clips' :func:`signature` (its index record): the 10th to
    the 90th percentile (a take of a right turn that turns left once left no turn excluded)."""
    found = [signature(m) for person in clips for m in person]
    return {key: [round(float(np.percentile([f[key] for f in found], q)), 3) for q in (10, 90)] for key in found[0]}


def file_name(action: str, axis: str) -> str:
    return f"{action}.{axis}.npz"


__all__ = [
    "ACTIONS",
    "CHOICE_FIT",
    "AXES",
    "LOCOMOTION",
    "PEOPLE",
    "SIGNATURE_MARGINS",
    "ShippedModel",
    "build",
    "candidates",
    "choose",
    "file_name",
    "fit",
    "index_records",
    "shipped_models",
    "signature",
    "signature_ranges",
    "training_clips",
]
