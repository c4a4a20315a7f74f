"""The method's defaults, defined once: training (:class:`TrainSettings`), editing
(:class:`EditSettings`) and validation (:class:`ValidationSettings`). The functions take their
keyword defaults from :data:`TRAINING`, :data:`EDITING` and :data:`VALIDATION`, the command line
its option defaults, and a model file's ``settings`` object fills its gaps from them."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any, Literal, Union

import numpy as np

from ..errors import ArgumentError

REPRESENTATIONS = ("rotvec", "euler")
CYCLE_CHOICES = ("all", "middle", "first", "whole", "gesture")
REFERENCES = ("model", "own")

CycleChoice = Union[str, int, tuple]
Reference = Literal["model", "own"]

# The entries a model file's settings object holds (in this order), and the JSON kinds of each.
_STORED = ("samples", "share", "energy", "rank", "degree", "cycle", "foot")
_KINDS: dict[str, tuple[tuple[type, ...], str]] = {
    "samples": ((int,), "an integer"),
    "share": ((int, float), "a number"),
    "energy": ((int, float), "a number"),
    "rank": ((int, type(None)), "an integer or null"),
    "degree": ((int,), "an integer"),
    "representation": ((str,), "text"),
    "cycle": ((str, int), "text or an integer"),
    "foot": ((int,), "an integer"),
}


@dataclass(frozen=True)
class TrainSettings:
    """What :func:`~expressive_mocap.exaggeration.train` was (or is to be) run with: ``samples`` a
    cycle (``T``), the expressiveness ``share`` of the key set, the basis' ``energy`` share of
    ``sum(s^2)`` unless ``rank`` is given, the mappings' polynomial ``degree``, the DOF
    ``representation``, each clip's ``cycle`` choice and the ``foot`` (0 = left) starting a cycle.

    Read from a model file's ``settings`` (:meth:`from_dict`), it also holds what :meth:`to_dict`
    needs to write that object back as it was: ``extra``, the entries this version does not know,
    and ``given``, the names of those it does that the file held (None: every one)."""

    samples: int = 50
    share: float = 0.9
    energy: float = 0.99
    rank: int | None = None
    degree: int = 1
    representation: str = "rotvec"
    cycle: CycleChoice = "all"
    foot: int = 0
    extra: Mapping[str, Any] = field(default_factory=dict, repr=False, hash=False)
    given: tuple[str, ...] | None = field(default=None, repr=False, compare=False)

    def to_dict(self) -> dict[str, Any]:
        """The JSON object a model file stores (the cycle choice as text; the representation is
        stored on its own): every entry, or those the file read held, then the unknown ones."""
        out = {name: getattr(self, name) for name in _STORED if self.given is None or name in self.given}
        if "cycle" in out:
            out["cycle"] = str(self.cycle)
        return {**out, **self.extra}

    @classmethod
    def from_dict(cls, settings: Mapping[str, Any]) -> TrainSettings:
        """From a model's ``settings``: missing entries take the defaults, unknown ones are kept
        in ``extra``; an :class:`~expressive_mocap.errors.ArgumentError` names an entry of the
        wrong kind."""
        if not isinstance(settings, Mapping):
            raise ArgumentError(f"settings must be a JSON object, got {type(settings).__name__}")
        known = {f.name for f in fields(cls)} - {"extra", "given"}
        for name, (kinds, text) in _KINDS.items():
            value = settings.get(name)
            if name in settings and not (isinstance(value, kinds) and not isinstance(value, bool)):
                raise ArgumentError(f"settings' {name} must be {text}, got {value!r}")
        return cls(
            **{k: v for k, v in settings.items() if k in known},
            extra={k: v for k, v in settings.items() if k not in known},
            given=tuple(k for k in settings if k in _STORED),
        )


@dataclass(frozen=True)
class EditSettings:
    """:func:`~expressive_mocap.exaggeration.exaggerate`'s defaults: the rotations' ``reference``
    ("model" or "own"), the clamping ``margin`` (share of the training range), the cross-``fade``
    at cycle boundaries and the foot locking's ``blend`` (seconds), whether to ``lock_feet``, and
    whether the current intensity's estimate reads each DOF's mean over the cycle as well as how
    it varies (``estimate_offsets``; False: an actor's own posture cannot move it), whether the
    cycles' duration and travel change with the intensity too (``timing``), and whether elbows and
    knees are kept within the bends training saw (``hinges``).

    Checked when made: an :class:`~expressive_mocap.errors.ArgumentError` names a bad value."""

    reference: Reference = "model"
    margin: float = 0.1
    fade: float = 0.15
    lock_feet: bool = True
    blend: float = 0.1
    estimate_offsets: bool = False
    timing: bool = True
    hinges: bool = True

    def __post_init__(self) -> None:
        if self.reference not in REFERENCES:
            raise ArgumentError(f"argument `reference`: expected 'model' or 'own', got {self.reference!r}")
        for name in ("margin", "fade", "blend"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
                raise ArgumentError(f"argument `{name}`: expected a number >= 0, got {value!r}")
            if not (np.isfinite(value) and value >= 0):
                raise ArgumentError(f"argument `{name}`: expected a finite number >= 0, got {value}")
            object.__setattr__(self, name, float(value))
        for name in ("lock_feet", "estimate_offsets", "timing", "hinges"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise ArgumentError(f"argument `{name}`: expected True or False, got {getattr(self, name)!r}")
            object.__setattr__(self, name, bool(getattr(self, name)))


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
    "Reference",
    "TrainSettings",
    "ValidationSettings",
]
