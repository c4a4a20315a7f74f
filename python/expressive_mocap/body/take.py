"""A :class:`Take`: one motion with its :class:`~expressive_mocap.body.Body` and what is derived
from it once: world rotations and positions, and whatever the steps of a command ask of it more
than once (the floor, foot contacts, features), kept on the take by the functions that compute
them (:meth:`Take.kept`).

Commands and the public edits build a take where a motion comes in and pass it down, so no step
runs forward kinematics, finds the floor or detects contacts again for the same motion.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Mapping
from functools import cached_property
from typing import TypeVar

import numpy as np
import numpy.typing as npt

from ..errors import ArgumentError
from ..motion import Motion
from .body import Body

T = TypeVar("T")
Array = npt.NDArray[np.float64]


class Take:
    """``motion`` with its ``body`` (default: the Body of its skeleton).

    A take assumes its motion is not changed in place while it is used (motions are not, in this
    package: edits return new ones)."""

    def __init__(self, motion: Motion, body: Body | None = None):
        if not isinstance(motion, Motion):
            raise ArgumentError(f"argument `motion`: expected a Motion, got {type(motion).__name__}")
        if body is not None and body.skeleton.content_key != motion.skeleton.content_key:
            raise ArgumentError("argument `body`: the Body of another skeleton than the motion's")
        self.motion = motion
        self.body = Body.of(motion.skeleton) if body is None else body
        self._kept: dict[Hashable, object] = {}

    @classmethod
    def of(cls, source: Motion | Take, user_map: Mapping[str, object] | None = None) -> Take:
        """``source`` itself when it is a take, else a new take of the motion (its Body read with
        ``user_map``, role -> joint name, where given)."""
        if isinstance(source, Take):
            return source
        if not isinstance(source, Motion):
            raise ArgumentError(f"argument `motion`: expected a Motion, got {type(source).__name__}")
        return cls(source, Body.of(source.skeleton, user_map))

    @cached_property
    def fk(self) -> tuple[Array, Array]:
        """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` (read-only)."""
        rotations, positions = self.motion.fk()
        rotations.setflags(write=False)
        positions.setflags(write=False)
        return rotations, positions

    @property
    def fk_if_computed(self) -> tuple[Array, Array] | None:
        """:attr:`fk` where something asked for it already, else None (for steps that need only
        a few frames' and would not compute every frame's for them)."""
        known = self.__dict__.get("fk")
        return None if known is None else (known[0], known[1])

    @property
    def positions(self) -> Array:
        """World positions ``[F, J, 3]`` (read-only)."""
        return self.fk[1]

    def kept(self, key: Hashable, compute: Callable[[], T]) -> T:
        """``compute()``, once per ``key`` for this take: how the functions deriving something from
        a take keep it (each with its own key, e.g. ``("contacts", settings)``)."""
        if key not in self._kept:
            self._kept[key] = compute()
        return self._kept[key]  # type: ignore[return-value]

    def __repr__(self) -> str:
        return f"Take({self.motion.n_frames} frames at {self.motion.fps:g} fps, {self.body!r})"


__all__ = ["Take"]
