"""Per-sample augmentation of windows, each transform with a probability: :class:`RandomRotation`
about the vertical, :class:`Mirror` (the window read from the clip's mirror image), :class:`Speed`,
:class:`Noise` and :class:`JointDropout`, put together by :class:`Compose`.

Every draw of a window depends on ``(seed, epoch, window index)`` alone: a counter-based hash
(SplitMix64) of those and of the transform's own stream gives its uniform numbers, so a window
gets the same angle, speed, mirror, noise and dropped joints whichever batch it is read in, with
whichever other windows, one by one or a batch at a time; and adding a transform to a
:class:`Compose` does not change the others' draws. Whether a transform applies to a window is
one more such draw against its ``p``.

The transforms are applied where they belong in reading a window, whatever their order in the
list: the mirror image and the speed decide which rows are read; then the window's own frame
(``frame="window"``), the rotation, normalisation, noise, and last the dropout, so that a dropped
joint is exactly zero (in normalised units when normalising: the channel's mean).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError

MASK64 = (1 << 64) - 1
STREAMS = {"rotation": 1, "speed": 2, "mirror": 3, "noise": 4, "dropout": 5}  # fixed: draws never move
NOISE_STREAM_INC = (0xDA3E39CB94B95BDB << 64) | 0x5851F42D4C957F2D  # odd: PCG64's stream of the noise
APPLY, VALUE = 0, 1  # a transform's two draws per window: whether it applies, and what it draws


def _mix(x):
    """SplitMix64's finaliser, on Python ints or uint64 arrays (wrapping)."""
    if isinstance(x, int):
        x = (x + 0x9E3779B97F4A7C15) & MASK64
        x = ((x ^ (x >> 30)) * 0xBF58476D1CE4E5B9) & MASK64
        x = ((x ^ (x >> 27)) * 0x94D049BB133111EB) & MASK64
        return x ^ (x >> 31)
    x = x + np.uint64(0x9E3779B97F4A7C15)
    x = (x ^ (x >> np.uint64(30))) * np.uint64(0xBF58476D1CE4E5B9)
    x = (x ^ (x >> np.uint64(27))) * np.uint64(0x94D049BB133111EB)
    return x ^ (x >> np.uint64(31))


def uniforms(seed: int, epoch: int, windows, stream: int, count: int = 1) -> np.ndarray:
    """``count`` numbers uniform in [0, 1) per window, ``[B, count]`` float64: a function of
    ``(seed, epoch, window, stream)`` only."""
    key = _mix(_mix(_mix(int(seed) & MASK64) ^ (int(epoch) & MASK64)) ^ stream)
    index = np.asarray(windows, dtype=np.int64).astype(np.uint64)
    with np.errstate(over="ignore"):
        base = _mix(index ^ np.uint64(key))[:, None]
        bits = _mix(base + np.arange(count, dtype=np.uint64) * np.uint64(0xD1B54A32D192ED03))
    return (bits >> np.uint64(11)).astype(np.float64) * 2.0**-53


def _probability(p) -> float:
    if isinstance(p, bool) or not isinstance(p, (int, float)) or not 0.0 <= p <= 1.0:
        raise ArgumentError(f"argument `p`: a probability in [0, 1], got {p!r}")
    return float(p)


class Transform:
    """What the transforms share: ``p``, the probability that a window gets it, and ``stream``,
    the name of its draws."""

    stream = ""
    p: float

    def applies(self, seed: int, epoch: int, windows) -> np.ndarray:
        """Whether each window gets this transform (``[B]`` bool)."""
        if self.p >= 1.0:
            return np.ones(len(windows), dtype=bool)
        if self.p <= 0.0:
            return np.zeros(len(windows), dtype=bool)
        return uniforms(seed, epoch, windows, STREAMS[self.stream] * 2 + APPLY)[:, 0] < self.p

    def values(self, seed: int, epoch: int, windows, count: int = 1) -> np.ndarray:
        return uniforms(seed, epoch, windows, STREAMS[self.stream] * 2 + VALUE, count)


@dataclass(frozen=True)
class RandomRotation(Transform):
    """A turn about the vertical by an angle uniform in [-``max_angle``, ``max_angle``) radians
    (default: any heading), with probability ``p``."""

    max_angle: float = math.pi
    p: float = 1.0
    stream = "rotation"

    def __post_init__(self):
        if not (isinstance(self.max_angle, (int, float)) and 0 <= self.max_angle <= math.pi):
            raise ArgumentError(f"argument `max_angle`: radians in [0, pi], got {self.max_angle!r}")
        object.__setattr__(self, "p", _probability(self.p))


@dataclass(frozen=True)
class Mirror(Transform):
    """The window read from the clip's mirror image instead (left for right), with probability
    ``p``: the same frames of ``X@mirrored`` for a clip ``X`` (and of ``X`` for ``X@mirrored``).
    Needs a dataset preprocessed with ``--mirror``."""

    p: float = 0.5
    stream = "mirror"

    def __post_init__(self):
        object.__setattr__(self, "p", _probability(self.p))


@dataclass(frozen=True)
class Speed(Transform):
    """The window played faster or slower by a factor drawn log-uniformly in ``factors``
    (``(0.8, 1.25)``: as often slower as faster), with probability ``p``."""

    factors: tuple[float, float] = (0.8, 1.25)
    p: float = 1.0
    stream = "speed"

    def __post_init__(self):
        try:
            low, high = (float(f) for f in self.factors)
        except (TypeError, ValueError):
            low, high = 0.0, -1.0
        if not 0 < low <= high:
            raise ArgumentError(f"argument `factors`: (low, high) with 0 < low <= high, got {self.factors!r}")
        object.__setattr__(self, "factors", (low, high))
        object.__setattr__(self, "p", _probability(self.p))


@dataclass(frozen=True)
class Noise(Transform):
    """Gaussian noise of std ``std`` on every float kind but contacts (after normalisation, when
    normalising: in units of each channel's std), or ``{kind: std}``, with probability ``p``."""

    std: float | Mapping[str, float] = 0.01
    p: float = 1.0
    stream = "noise"

    def __post_init__(self):
        stds = self.std.values() if isinstance(self.std, Mapping) else [self.std]
        if any(isinstance(s, bool) or not isinstance(s, (int, float)) or not s >= 0 for s in stds):
            raise ArgumentError(f"argument `std`: a non-negative number or {{kind: number}}, got {self.std!r}")
        object.__setattr__(self, "p", _probability(self.p))

    def of(self, kind: str) -> float:
        return float(self.std.get(kind, 0.0)) if isinstance(self.std, Mapping) else float(self.std)


@dataclass(frozen=True)
class JointDropout(Transform):
    """With probability ``p``, each joint (of ``joints``, names or indices; all by default) dropped
    with probability ``rate``: its values zeroed in every kind with a joint axis, and
    ``batch["dropped"]`` ``[B, J]`` True there, for a loss to mask."""

    rate: float = 0.1
    p: float = 1.0
    joints: Sequence[str | int] | None = field(default=None)
    stream = "dropout"

    def __post_init__(self):
        if isinstance(self.rate, bool) or not isinstance(self.rate, (int, float)) or not 0 <= self.rate <= 1:
            raise ArgumentError(f"argument `rate`: a probability in [0, 1], got {self.rate!r}")
        if self.joints is not None:
            object.__setattr__(self, "joints", tuple(self.joints))
        object.__setattr__(self, "p", _probability(self.p))

    def droppable(self, names: Sequence[str]) -> np.ndarray:
        """``[J]`` bool: the joints of a skeleton of ``names`` that may drop."""
        mask = np.zeros(len(names), dtype=bool)
        if self.joints is None:
            mask[:] = True
            return mask
        for joint in self.joints:
            if isinstance(joint, str):
                if joint not in names:
                    raise ArgumentError(f"argument `joints`: no joint {joint!r} in the skeleton")
                mask[list(names).index(joint)] = True
            elif isinstance(joint, (int, np.integer)) and -len(names) <= joint < len(names):
                mask[joint] = True
            else:
                raise ArgumentError(f"argument `joints`: names or indices of {len(names)} joints, got {joint!r}")
        return mask


@dataclass
class Draws:
    """What was drawn for a batch's windows: ``angle`` (radians, 0 when not rotated), ``speed``
    (1 when not), ``mirrored``, ``noised`` (``[B]``), ``dropped`` (``[B, J]``), and the ``seed``,
    ``epoch`` and ``window`` indices they come from."""

    seed: int
    epoch: int
    window: np.ndarray
    angle: np.ndarray
    speed: np.ndarray
    mirrored: np.ndarray
    noised: np.ndarray
    dropped: np.ndarray

    def take(self, order: np.ndarray) -> Draws:
        """The draws of the windows ``order`` (indices into this batch)."""
        return Draws(
            self.seed,
            self.epoch,
            self.window[order],
            self.angle[order],
            self.speed[order],
            self.mirrored[order],
            self.noised[order],
            self.dropped[order],
        )

    def noise_streams(self, which) -> Iterator[np.random.Generator]:
        """A generator of the noise of each of windows ``which`` (places in this batch), in turn:
        one PCG64 whose state is set, for each window, from a hash of its seed, epoch and window
        index alone (setting a state costs far less than seeding a generator)."""
        halves = uniforms(self.seed, self.epoch, self.window[which], STREAMS["noise"] * 2 + VALUE, 2)
        halves = (halves * 2.0**53).astype(np.uint64)
        bits = np.random.PCG64()
        generator = np.random.Generator(bits)
        for high, low in halves.tolist():
            state = {"state": (high << 75) ^ (low << 11) ^ high, "inc": NOISE_STREAM_INC}
            bits.state = {"bit_generator": "PCG64", "state": state, "has_uint32": 0, "uinteger": 0}  # type: ignore[typeddict-item]
            yield generator


class Compose:
    """Transforms applied together: ``Compose([RandomRotation(p=0.5), Mirror(p=0.5), Speed((0.8,
    1.25), p=0.3), Noise(0.01, p=0.2), JointDropout(0.1, p=0.2)])``, at most one of each kind;
    each in its place in reading a window (this module's notes), whatever the list's order."""

    def __init__(self, transforms: Sequence[Transform] = ()):
        self.transforms = list(transforms)
        kinds: dict[type, Transform] = {}
        for t in self.transforms:
            if not isinstance(t, Transform):
                raise ArgumentError(
                    f"argument `transforms`: RandomRotation, Mirror, Speed, Noise or JointDropout, got {t!r}"
                )
            if type(t) in kinds:
                raise ArgumentError(f"argument `transforms`: {type(t).__name__} given twice")
            kinds[type(t)] = t
        self.rotation = _get(kinds, RandomRotation)
        self.mirror = _get(kinds, Mirror)
        self.speed = _get(kinds, Speed)
        self.noise = _get(kinds, Noise)
        self.dropout = _get(kinds, JointDropout)

    def __repr__(self) -> str:
        return f"Compose({self.transforms!r})"

    @property
    def active(self) -> bool:
        return any(t.p > 0 for t in self.transforms)

    @property
    def rotates(self) -> bool:
        return self.rotation is not None and self.rotation.p > 0 and self.rotation.max_angle > 0

    @property
    def mirrors(self) -> bool:
        return self.mirror is not None and self.mirror.p > 0

    def draw(self, seed: int, epoch: int, windows, droppable: np.ndarray) -> Draws:
        """The draws of ``windows`` (indices) at ``seed`` and ``epoch``; ``droppable`` ``[J]`` the
        joints a dropout may take."""
        windows = np.asarray(windows, dtype=np.int64)
        n, joints = len(windows), len(droppable)
        angle, speed = np.zeros(n), np.ones(n)
        mirrored, noised = np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
        dropped = np.zeros((n, joints), dtype=bool)
        if self.rotation is not None and self.rotates:
            limit = self.rotation.max_angle
            value = (2.0 * self.rotation.values(seed, epoch, windows)[:, 0] - 1.0) * limit
            angle = np.where(self.rotation.applies(seed, epoch, windows), value, 0.0)
        if self.speed is not None:
            low, high = np.log(self.speed.factors[0]), np.log(self.speed.factors[1])
            value = np.exp(low + (high - low) * self.speed.values(seed, epoch, windows)[:, 0])
            speed = np.where(self.speed.applies(seed, epoch, windows), value, 1.0)
        if self.mirror is not None:
            mirrored = self.mirror.applies(seed, epoch, windows)
        if self.noise is not None:
            noised = self.noise.applies(seed, epoch, windows)
        if self.dropout is not None and self.dropout.rate > 0:
            drop = self.dropout.values(seed, epoch, windows, joints) < self.dropout.rate
            dropped = drop & droppable[None, :] & self.dropout.applies(seed, epoch, windows)[:, None]
        return Draws(seed, epoch, windows, angle, speed, mirrored, noised, dropped)


def _get(kinds: dict, cls):
    return kinds.get(cls)


__all__ = [
    "STREAMS",
    "Compose",
    "Draws",
    "JointDropout",
    "Mirror",
    "Noise",
    "RandomRotation",
    "Speed",
    "Transform",
    "uniforms",
]
