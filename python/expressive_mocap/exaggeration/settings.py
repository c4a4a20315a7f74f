"""The method's defaults, defined once: training (:class:`TrainSettings`), editing
(:class:`EditSettings`) and validation (:class:`ValidationSettings`). The functions take their
keyword defaults from :data:`TRAINING`, :data:`EDITING` and :data:`VALIDATION`, the command line
its option defaults, and a model file's ``settings`` object fills its gaps from them."""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Any, Union

REPRESENTATIONS = ("rotvec", "euler")
CYCLE_CHOICES = ("all", "middle", "first", "whole")
REFERENCES = ("model", "own")

CycleChoice = Union[str, int, tuple]


@dataclass(frozen=True)
class TrainSettings:
    """What :func:`~expressive_mocap.exaggeration.train` was (or is to be) run with: ``samples`` a
    cycle (``T``), the expressiveness ``share`` of the key set, the basis' ``energy`` share of
    ``sum(s^2)`` unless ``rank`` is given, the mappings' polynomial ``degree``, the DOF
    ``representation``, each clip's ``cycle`` choice and the ``foot`` (0 = left) starting a cycle."""

    samples: int = 50
    share: float = 0.9
    energy: float = 0.99
    rank: int | None = None
    degree: int = 1
    representation: str = "rotvec"
    cycle: CycleChoice = "all"
    foot: int = 0

    def to_dict(self) -> dict[str, Any]:
        """The JSON object a model file stores (the cycle choice as text)."""
        out = asdict(self)
        del out["representation"]  # stored on its own in the model file
        out["cycle"] = str(self.cycle)
        return out

    @classmethod
    def from_dict(cls, settings: dict[str, Any]) -> TrainSettings:
        """From a model's ``settings`` (missing entries take the defaults; unknown ones are ignored)."""
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in settings.items() if k in known})


@dataclass(frozen=True)
class EditSettings:
    """:func:`~expressive_mocap.exaggeration.exaggerate`'s defaults: the rotations' ``reference``
    ("model" or "own"), the clamping ``margin`` (share of the training range), the cross-``fade``
    at cycle boundaries and the foot locking's ``blend`` (seconds), whether to ``lock_feet``, and
    whether the current intensity's estimate reads each DOF's mean over the cycle as well as how
    it varies (``estimate_offsets``; False: an actor's own posture cannot move it), and whether the
    cycles' duration and travel change with the intensity too (``timing``)."""

    reference: str = "model"
    margin: float = 0.1
    fade: float = 0.15
    lock_feet: bool = True
    blend: float = 0.1
    estimate_offsets: bool = False
    timing: bool = True


@dataclass(frozen=True)
class ValidationSettings:
    """:func:`~expressive_mocap.exaggeration.swap_test`'s random same-size sets: how many
    (``draws``) and the ``seed``."""

    draws: int = 200
    seed: int = 0


TRAINING = TrainSettings()
EDITING = EditSettings()
VALIDATION = ValidationSettings()

__all__ = [
    "CYCLE_CHOICES",
    "EDITING",
    "REFERENCES",
    "REPRESENTATIONS",
    "TRAINING",
    "VALIDATION",
    "CycleChoice",
    "EditSettings",
    "TrainSettings",
    "ValidationSettings",
]
