"""What a body model records of its training, as typed records: :class:`BodyModelSettings` (what
:func:`~expressive_mocap.decoupling.train_body_model` was run with) and :class:`TrainingReport`
(the scores of every stage, :class:`StageScores`, on the :class:`Split`). A model file holds them
as JSON objects (its ``settings`` and ``report``); every field is None where a file has no such
entry, and entries this version does not know are kept in ``extra`` and written back
(:mod:`expressive_mocap._utils.records`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from .._utils.records import read_record, record_json


@dataclass(frozen=True)
class BodyModelSettings:
    """What training was run with: the autoencoder's code units (``hidden``) and the regression's
    (``regression_hidden``), the ``seed``, L-BFGS iterations per stage (``max_iter``), the neutral
    clips and their frames, the unlabelled clips and the frames drawn from them (with the neutral
    training frames) for the autoencoder, and how the ``features`` and their ``feature_range``
    were taken (text)."""

    hidden: int | None = None
    regression_hidden: int | None = None
    seed: int | None = None
    max_iter: int | None = None
    neutral_clips: int | None = None
    neutral_frames: int | None = None
    unlabelled_clips: int | None = None
    unlabelled_frames: int | None = None
    features: str | None = None
    feature_range: str | None = None
    extra: dict[str, Any] = field(default_factory=dict, repr=False, hash=False)

    @classmethod
    def from_json(cls, value: Any, where: str = "settings") -> BodyModelSettings:
        """From a model file's ``settings`` object (a :class:`ModelError` naming a bad entry)."""
        return read_record(cls, value, where)

    def to_json(self) -> dict[str, Any]:
        """The JSON object a model file stores."""
        return record_json(self)


@dataclass(frozen=True)
class Split:
    """The 70/30 split by clip: rows (frames) and groups (clips) on each side."""

    train_rows: int | None = None
    test_rows: int | None = None
    train_groups: int | None = None
    test_groups: int | None = None
    extra: dict[str, Any] = field(default_factory=dict, repr=False, hash=False)

    def to_json(self) -> dict[str, Any]:
        """The JSON object a model file stores."""
        return record_json(self)


@dataclass(frozen=True)
class StageScores:
    """One stage's mean squared errors on the training and test rows, the share of the test poses'
    variance it explains, and where measured the ``seconds`` it took, its ``hidden`` units and its
    L-BFGS ``iterations``."""

    train_mse: float | None = None
    test_mse: float | None = None
    test_variance_explained: float | None = None
    seconds: float | None = None
    hidden: int | None = None
    iterations: int | None = None
    extra: dict[str, Any] = field(default_factory=dict, repr=False, hash=False)

    def to_json(self) -> dict[str, Any]:
        """The JSON object a model file stores."""
        return record_json(self)


@dataclass(frozen=True)
class TrainingReport:
    """The scores of every stage of training (``regression`` in code units, every other stage in
    pose units; ``plain`` the one-hidden-layer network compared with), on the ``split``, with
    ``test_variance`` the mean per-column variance of the test poses."""

    split: Split | None = None
    test_variance: float | None = None
    mean_pose: StageScores | None = None
    autoencoder: StageScores | None = None
    regression: StageScores | None = None
    stack: StageScores | None = None
    fine_tuned: StageScores | None = None
    plain: StageScores | None = None
    extra: dict[str, Any] = field(default_factory=dict, repr=False, hash=False)

    STAGES = ("mean_pose", "autoencoder", "regression", "stack", "fine_tuned", "plain")

    def stages(self) -> dict[str, StageScores]:
        """The stages reported, by name, in training's order."""
        return {name: s for name in self.STAGES if (s := getattr(self, name)) is not None}

    def table(self) -> str:
        """The report as a small table: one line per stage (``?`` where the report has no value)."""
        split = self.split.to_json() if self.split is not None else None
        lines = [
            f"split: {split}, test variance {_number(self.test_variance, '.4g')}",
            f"{'stage':12s} {'train MSE':>10s} {'test MSE':>10s} {'test var. expl.':>15s} {'seconds':>8s}",
        ]
        for stage, r in self.stages().items():
            lines.append(
                f"{stage:12s} {_number(r.train_mse, '10.4g')} {_number(r.test_mse, '10.4g')} "
                f"{_number(r.test_variance_explained, '15.4f')} {_number(r.seconds or 0.0, '8.1f')}"
            )
        lines.append("(regression in code units; every other stage in pose units)")
        return "\n".join(lines)

    @classmethod
    def from_json(cls, value: Any, where: str = "report") -> TrainingReport:
        """From a model file's ``report`` object (a :class:`ModelError` naming a bad entry)."""
        return read_record(cls, value, where)

    def to_json(self) -> dict[str, Any]:
        """The JSON object a model file stores."""
        return record_json(self)


def _number(value: float | None, spec: str) -> str:
    """``value`` formatted by ``spec``, or ``?`` as wide where a report has none."""
    return format(value, spec) if value is not None else format("?", f">{spec.split('.')[0] or 1}")


__all__ = ["BodyModelSettings", "Split", "StageScores", "TrainingReport"]
