"""The data model: a :class:`Skeleton` (hierarchy, rest offsets, BVH channel layout) and a
:class:`Motion` (a skeleton, a frame time, local rotations and translations per frame).

Conventions: quaternions x, y, z, w; ``rotations [F, J, 4]`` and ``translations [F, J, 3]`` are
local to each joint's parent; a translation is the joint's rest offset, with the components
replaced by the position channels wherever the joint has them (root included). Y is up, lengths
are in the file's units.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property, lru_cache

import numpy as np

from . import ops
from ._utils.tokens import listed, shown
from .bvh.tree import channel_summary, vertical_extent
from .errors import MocapError
from .rotations import quat
from .rotations.orders import (
    ROTATION_CHANNELS,
    axes_of,
    canonical_channels,
    order_name,
    rotation_order,
)


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@lru_cache(maxsize=256)
def _channel_lists(channels: tuple[tuple[str, ...], ...]) -> tuple[tuple[tuple[str, ...], ...], int]:
    """:func:`canonical_channels` of every joint's list, and the first joint that lists a channel
    twice (-1: none). Cached: skeletons are made for every clip read, from a handful of layouts."""
    canonical = tuple(canonical_channels(cs) for cs in channels)
    return canonical, next((j for j, cs in enumerate(canonical) if len(set(cs)) != len(cs)), -1)


def _checked_offsets(
    joints: int, offsets: np.ndarray, site_joints: list[int], site_offsets: np.ndarray
) -> tuple[np.ndarray, tuple]:
    """The checks of a skeleton's rest offsets ``[J, 3]`` and End Sites (the joint each is attached
    to, and its offset; float64 arrays): read-only offsets and the End Sites as ``(joint, offset)``
    tuples of Python numbers, or a MocapError."""
    if not np.isfinite(offsets).all():
        raise MocapError("joint offsets must be finite")
    if not np.isfinite(site_offsets).all():
        raise MocapError("End Site offsets must be finite")
    if site_joints and not (min(site_joints) >= 0 and max(site_joints) < joints):
        j = next(j for j in site_joints if not 0 <= j < joints)
        raise MocapError(f"End Site attached to joint {j}, but there are {joints} joints")
    return _frozen(offsets), tuple(zip(site_joints, map(tuple, site_offsets.tolist())))


@lru_cache(maxsize=256)
def _euler_orders(channels: tuple[tuple[str, ...], ...]) -> np.ndarray:
    """See :attr:`Skeleton.euler_orders`. Cached: archives share a handful of channel layouts."""
    return _frozen(np.array([axes_of(rotation_order(cs)) for cs in channels], dtype=np.uint8).reshape(-1, 3))


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A joint hierarchy with its BVH channel names, enough to write a file back as it came (the
    channel layout of a frame, and encoding and decoding it, are in :mod:`expressive_mocap.bvh.channels`).

    ``names[j]``, ``parents[j]`` (-1 for the root; parents come before children, depth first),
    ``offsets[j]`` (rest offset from the parent), ``channels[j]`` (channel names in file order,
    e.g. ``("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")``),
    ``end_sites`` (``(joint, offset)`` pairs, the BVH End Sites, which are not joints).
    """

    names: tuple[str, ...]
    parents: np.ndarray
    offsets: np.ndarray
    channels: tuple[tuple[str, ...], ...]
    end_sites: tuple[tuple[int, tuple[float, float, float]], ...] = field(default=())

    def __post_init__(self):
        names = tuple(map(str, self.names))
        parents = np.array(self.parents, dtype=np.int64).reshape(-1)
        offsets = np.array(self.offsets, dtype=np.float64)
        channels, listed_twice = _channel_lists(tuple(map(tuple, self.channels)))
        joints = len(names)
        if joints == 0:
            raise MocapError("a skeleton needs at least one joint")
        if len(parents) != joints or offsets.shape != (joints, 3) or len(channels) != joints:
            raise MocapError(
                f"skeleton parts disagree: {joints} names, {len(parents)} parents, offsets "
                f"{list(offsets.shape)}, {len(channels)} channel lists"
            )
        if len(set(names)) != joints:
            duplicate = next(n for n in names if names.count(n) > 1)
            raise MocapError(f"joint name {shown(duplicate)} appears more than once")
        later = parents[1:]
        if parents[0] != -1 or not ((later >= 0) & (later < np.arange(1, joints))).all():
            if parents[0] != -1 or (later < 0).any():
                raise MocapError("a skeleton has exactly one root, the first joint (parent -1)")
            raise MocapError("every joint must come after its parent")
        site_offsets = np.array([off for _, off in self.end_sites], dtype=np.float64)
        offsets, end_sites = _checked_offsets(joints, offsets, [int(j) for j, _ in self.end_sites], site_offsets)
        if listed_twice >= 0:
            raise MocapError(f"joint {names[listed_twice]!r} lists a channel twice: {' '.join(channels[listed_twice])}")
        self._set(names, _frozen(parents), offsets, channels, end_sites)

    def _set(self, names, parents, offsets, channels, end_sites) -> None:
        """Set the fields of a checked skeleton (the dataclass is frozen)."""
        fields = {"names": names, "parents": parents, "offsets": offsets, "channels": channels, "end_sites": end_sites}
        for name, value in fields.items():
            object.__setattr__(self, name, value)

    def __repr__(self) -> str:
        # One line: the dataclass default prints every offset.
        sites = f", {len(self.end_sites)} End Sites" if self.end_sites else ""
        return f"Skeleton({self.n_joints} joints, root {self.names[0]!r}{sites}, {self.n_channels} channels)"

    @property
    def n_joints(self) -> int:
        return len(self.names)

    @cached_property
    def n_channels(self) -> int:
        """Numbers per frame in the MOTION block."""
        return sum(len(cs) for cs in self.channels)

    def index(self, name: str) -> int:
        """Index of the joint called ``name``."""
        try:
            return self.names.index(name)
        except ValueError:
            raise MocapError(f"no joint named {shown(str(name))}; joints are: {listed(self.names)}") from None

    def rotation_order(self, joint: int) -> str:
        """The joint's Euler order as written (e.g. ``"ZXY"``); axes without a channel follow
        in X, Y, Z order (their angle is always 0); ``"XYZ"`` for a joint without rotations."""
        return rotation_order(self.channels[joint])

    @property
    def euler_orders(self) -> np.ndarray:
        """``[J, 3]`` uint8 axis indices of every joint's rotation order."""
        return _euler_orders(self.channels)

    def layout(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where each joint's numbers sit in a frame of channel values: see
        :func:`expressive_mocap.bvh.channels.layout`."""
        from .bvh.channels import layout  # imported here: the bvh package imports this module

        return layout(self)

    def with_rotation_order(self, order: str) -> Skeleton:
        """The same skeleton with every joint's rotation channels written in ``order``
        (joints with some rotation channels get all three, where the first one stood)."""
        order = order_name(axes_of(order))
        channels = []
        for cs in self.channels:
            first = next((i for i, c in enumerate(cs) if c in ROTATION_CHANNELS), None)
            if first is None:
                channels.append(cs)
                continue
            kept = [c for c in cs if c not in ROTATION_CHANNELS]
            position = sum(1 for c in cs[:first] if c not in ROTATION_CHANNELS)
            channels.append(tuple(kept[:position]) + tuple(f"{a}rotation" for a in order) + tuple(kept[position:]))
        return Skeleton(self.names, self.parents, self.offsets, tuple(channels), self.end_sites)

    def with_offsets(self, offsets, end_site_offsets) -> Skeleton:
        """The same hierarchy and channels with other rest offsets: joints ``[J, 3]``, End Sites ``[E, 3]``."""
        offsets = np.array(offsets, dtype=np.float64)
        site_offsets = np.array(end_site_offsets, dtype=np.float64).reshape(-1, 3)
        if offsets.shape != self.offsets.shape or len(site_offsets) != len(self.end_sites):
            raise MocapError(
                f"with_offsets: expected {list(self.offsets.shape)} joint and {len(self.end_sites)} End Site offsets"
            )
        # The private constructor path: the hierarchy and channels are this skeleton's (immutable,
        # checked when it was made), the new offsets get the constructor's checks. Constructing
        # anew would check everything again, 10x the time, on every clip of a known hierarchy read.
        site_joints = [j for j, _ in self.end_sites]
        joint_offsets, sites = _checked_offsets(self.n_joints, offsets, site_joints, site_offsets)
        copy = object.__new__(Skeleton)
        copy._set(self.names, self.parents, joint_offsets, self.channels, sites)
        return copy

    def scaled(self, factor: float) -> Skeleton:
        """The same skeleton with every length multiplied by ``factor``."""
        with np.errstate(over="ignore", invalid="ignore"):
            offsets = self.offsets * factor
            sites = tuple((j, tuple(np.multiply(off, factor))) for j, off in self.end_sites)
        if not (np.isfinite(offsets).all() and np.isfinite([off for _, off in sites]).all()):
            lengths = np.concatenate([self.offsets.ravel(), np.ravel([off for _, off in self.end_sites])])
            _not_finite(factor, "an offset", np.abs(lengths).max(initial=0.0))
        return Skeleton(self.names, self.parents, offsets, self.channels, sites)

    @cached_property
    def content_key(self) -> tuple:
        """What tells this skeleton from another, by content (two files of one rig read alike,
        where the skeletons themselves hash by identity): a key for the caches and groupings of
        skeletons met across clips."""
        return (self.names, self.parents.tobytes(), self.offsets.tobytes(), self.channels)

    def rest_positions(self) -> tuple[np.ndarray, np.ndarray]:
        """World positions of the joints ``[J, 3]`` and End Sites ``[E, 3]`` in the rest pose
        (identity rotations, offsets only); read-only arrays."""
        return self._rest

    @cached_property
    def _rest(self) -> tuple[np.ndarray, np.ndarray]:
        # Cached: the skeleton is immutable, and archives ask for it once per clip, several times.
        identity = np.zeros((1, self.n_joints, 4))
        identity[..., 3] = 1.0
        _, positions = ops.forward_kinematics(identity, self.offsets[None], self.parents)
        joints = positions[0]
        sites = np.array([joints[j] + off for j, off in self.end_sites]).reshape(-1, 3)
        return _frozen(joints), _frozen(sites)

    def rest_height(self) -> float:
        """Vertical (Y) extent of the rest pose, End Sites included."""
        return vertical_extent(self.parents.tolist(), self.offsets[:, 1].tolist(), self.end_sites)

    def channel_layout(self) -> str:
        """A one-line summary such as ``22 joints x 6 (Xposition Yposition ... Yrotation)``."""
        return channel_summary(self.channels)


def _not_finite(factor, what: str, largest: float):
    raise MocapError(
        f"scaled: x {factor:g} takes {what} beyond float64 (the largest is {largest:.6g}): lengths must stay finite"
    )


# The most frames x joints Motion.resample makes (docs/safety.md, "Limits"): 2^25, 1.9 GB of rotations and
# translations at 56 bytes a joint-frame. The largest file the reader takes at a realistic density
# (512 MiB of text, ~13 million joint-frames: half an hour of 60 joints at 120 fps) fits at twice
# its rate; a 300-byte file claiming a frame time of 10^6 s does not ask for 7 GiB.
MAX_RESAMPLED_JOINT_FRAMES = 1 << 25
_RESAMPLE_BLOCK = 1 << 18  # joint-frames interpolated at a time


class Motion:
    """A skeleton in motion: local ``rotations [F, J, 4]`` (x, y, z, w, unit) and
    ``translations [F, J, 3]`` per frame, ``frame_time`` seconds apart.

    Index it with a slice or frame indices to get a shorter motion: ``motion[30:90]``.
    """

    def __init__(self, skeleton: Skeleton, rotations, translations, frame_time: float):
        rotations = np.ascontiguousarray(rotations, dtype=np.float64)
        translations = np.ascontiguousarray(translations, dtype=np.float64)
        joints = skeleton.n_joints
        if rotations.ndim != 3 or rotations.shape[1:] != (joints, 4):
            raise MocapError(f"rotations: expected shape [F, {joints}, 4], got {list(rotations.shape)}")
        if translations.shape != rotations.shape[:2] + (3,):
            raise MocapError(
                f"translations: expected shape [{len(rotations)}, {joints}, 3], got {list(translations.shape)}"
            )
        if not (np.isfinite(frame_time) and frame_time > 0):
            raise MocapError(f"frame_time must be a positive number of seconds, got {frame_time}")
        self.skeleton = skeleton
        self.rotations = rotations
        self.translations = translations
        self.frame_time = float(frame_time)

    def __repr__(self) -> str:
        return f"Motion({self.n_frames} frames at {self.fps:g} fps, {self.skeleton.n_joints} joints)"

    @property
    def n_frames(self) -> int:
        return len(self.rotations)

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    @property
    def duration(self) -> float:
        """Seconds from the first frame to the last."""
        return max(self.n_frames - 1, 0) * self.frame_time

    def __len__(self) -> int:
        return self.n_frames

    def __getitem__(self, frames) -> Motion:
        if isinstance(frames, (int, np.integer)):
            frames = [frames]
        return Motion(self.skeleton, self.rotations[frames], self.translations[frames], self.frame_time)

    @classmethod
    def from_euler(
        cls,
        skeleton: Skeleton,
        angles,
        translations=None,
        frame_time: float = 1 / 30,
        order: str | Sequence[str] | None = None,
    ) -> Motion:
        """A motion from Euler angles ``[F, J, 3]`` in degrees, in each joint's own rotation
        order (or ``order``); ``translations`` default to the rest offsets."""
        angles = np.asarray(angles, dtype=np.float64)
        orders = skeleton.euler_orders if order is None else order
        rotations = ops.euler_to_quat(angles, orders)
        if translations is None:
            translations = np.broadcast_to(skeleton.offsets, angles.shape[:2] + (3,))
        return cls(skeleton, rotations, translations, frame_time)

    def to_euler(self, order: str | Sequence[str] | None = None) -> np.ndarray:
        """Euler angles ``[F, J, 3]`` in degrees, in each joint's own rotation order (or ``order``)."""
        return ops.quat_to_euler(self.rotations, self.skeleton.euler_orders if order is None else order)

    def fk(self) -> tuple[np.ndarray, np.ndarray]:
        """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` of every joint."""
        return ops.forward_kinematics(self.rotations, self.translations, self.skeleton.parents)

    def positions(self) -> np.ndarray:
        """World positions ``[F, J, 3]`` of every joint, in file units."""
        return self.fk()[1]

    def channel_values(self) -> np.ndarray:
        """The BVH channel values ``[F, C]`` of every frame, in the skeleton's layout."""
        from .bvh.channels import encode  # imported here: the bvh package imports this module

        return encode(self.skeleton, self.rotations, self.translations)

    def resample(self, fps: float | None = None, n_frames: int | None = None) -> Motion:
        """The same movement sampled at ``fps`` frames a second, or with ``n_frames`` frames over the
        same duration: slerp for rotations, linear for translations.

        The output may hold at most :data:`MAX_RESAMPLED_JOINT_FRAMES` frames x joints, checked
        from the frame count computed in floating point before anything is allocated (a 2-frame
        file claiming a frame time of 10^6 s asks 120 fps for 1.2 x 10^8 frames); it is then filled
        in blocks, so the peak memory is the output's 56 bytes a joint-frame and a little more."""
        if (fps is None) == (n_frames is None):
            raise MocapError("resample: give exactly one of fps or n_frames")
        if self.n_frames < 2:
            raise MocapError("resample: a motion needs at least 2 frames")
        joints = self.skeleton.n_joints
        if fps is not None:
            if (
                isinstance(fps, bool)
                or not isinstance(fps, (int, float, np.integer, np.floating))
                or not (np.isfinite(fps) and fps > 0)
            ):
                raise MocapError(f"resample: fps must be a positive finite number, got {fps!r}")
            new_time = 1.0 / float(fps)
            # Files round the frame time (0.0333333 for 1/30 s): allow a hundredth of a frame.
            frames = np.floor(self.duration / new_time + 0.01) + 1  # a float: may be 1e302 or inf
            what = f"{float(fps):g} fps over {self.duration:g} s"
        else:
            if isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer)) or n_frames < 2:
                raise MocapError(f"resample: n_frames must be a whole number of at least 2, got {n_frames!r}")
            frames, what = n_frames, "n_frames"
            new_time = self.duration / (n_frames - 1)
        if not frames * joints <= MAX_RESAMPLED_JOINT_FRAMES:
            raise MocapError(
                f"resample: {what} is {frames:.6g} frames x {joints} joints, more than the "
                f"{MAX_RESAMPLED_JOINT_FRAMES:,} "
                f"joint-frames (56 bytes each) a resampled motion may have"
            )
        if not (
            np.isfinite(new_time) and new_time > 0
        ):  # 1e-320 fps overflows, n_frames over a tiny duration underflows
            raise MocapError(f"resample: {what} gives a frame time of {new_time:g} s")
        n_frames = int(frames)
        rotations = np.empty((n_frames, joints, 4))
        translations = np.empty((n_frames, joints, 3))
        block = max(1, _RESAMPLE_BLOCK // joints)  # slerp's temporaries take ~5x its output
        for first in range(0, n_frames, block):
            rows = slice(first, min(first + block, n_frames))
            position = np.minimum(np.arange(rows.start, rows.stop) * new_time / self.frame_time, self.n_frames - 1)
            rotations[rows] = quat.resample(self.rotations, position)
            translations[rows] = quat.resample(self.translations, position, rotations=False)
        return Motion(self.skeleton, rotations, translations, new_time)

    def scaled(self, factor: float) -> Motion:
        """The same motion with every length (offsets, translations) multiplied by ``factor``."""
        skeleton = self.skeleton.scaled(factor)
        with np.errstate(over="ignore", invalid="ignore"):
            translations = self.translations * factor
        if not np.isfinite(translations).all():
            _not_finite(factor, "a translation", np.abs(self.translations).max(initial=0.0))
        return Motion(skeleton, self.rotations, translations, self.frame_time)

    def with_rotation_order(self, order: str) -> Motion:
        """The same motion, to be written with every joint's rotation channels in ``order``."""
        return Motion(self.skeleton.with_rotation_order(order), self.rotations, self.translations, self.frame_time)


def spread_frames(n_frames: int, count: int) -> np.ndarray:
    """At most ``count`` frame indices spread evenly over ``n_frames`` frames, first and last
    included: what a reading over a clip's frames samples."""
    return np.unique(np.linspace(0, n_frames - 1, min(n_frames, count)).astype(int))


__all__ = [
    "Motion",
    "Skeleton",
    "spread_frames",
]
