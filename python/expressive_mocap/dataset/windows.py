"""Sliding windows over a dataset's clips, never across a clip's boundary.

A window is ``length`` frames of one clip, starting every ``stride`` frames from the clip's
first. Its tail, when the clip's frames do not end on a window: ``"drop"`` leaves it out (a clip
shorter than a window gives none), ``"edge"`` adds one more window whose frames past the clip's
end repeat its last frame, ``"zero"`` one whose missing frames are zeros. A window that needs no
padding, read from a memory-mapped array, is a view of it (a slice: no copy, no read until used).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..errors import ArgumentError

PADDING = ("drop", "edge", "zero")


class Windows:
    """The windows of the clips ``clips`` (indices; all by default) of a dataset, or of
    ``offsets`` ``[C + 1]`` (clip ``i`` is rows ``offsets[i]:offsets[i + 1]``).

    Attributes (one entry per window, clip by clip, in order): ``clip`` (clip index), ``start``
    (first row of the window in the dataset's arrays), ``offset`` (its first frame within the
    clip), ``valid`` (frames that are the clip's own: ``length`` except in a padded tail) and
    ``end`` (the clip's end row). ``len(windows)`` windows; ``windows.rows(i)`` the rows of
    window ``i`` (clamped to its clip's last row); ``windows.read(array, i)`` its frames."""

    def __init__(
        self,
        dataset_or_offsets,
        length: int,
        stride: int | None = None,
        padding: str = "drop",
        clips: Sequence[int] | np.ndarray | None = None,
    ):
        offsets = np.asarray(getattr(dataset_or_offsets, "offsets", dataset_or_offsets), dtype=np.int64)
        stride = length if stride is None else stride
        if not isinstance(length, (int, np.integer)) or length < 1:
            raise ArgumentError(f"argument `length`: a positive number of frames, got {length!r}")
        if not isinstance(stride, (int, np.integer)) or stride < 1:
            raise ArgumentError(f"argument `stride`: a positive number of frames, got {stride!r}")
        if padding not in PADDING:
            raise ArgumentError(f"argument `padding`: one of {', '.join(PADDING)}, got {padding!r}")
        self.length, self.stride, self.padding = int(length), int(stride), padding
        count = len(offsets) - 1
        chosen = np.arange(count) if clips is None else np.asarray(clips, dtype=np.int64)
        if chosen.size and (chosen.min() < 0 or chosen.max() >= count):
            raise ArgumentError(f"argument `clips`: indices of a dataset of {count} clips expected")
        begins, ends = offsets[chosen], offsets[chosen + 1]
        frames = ends - begins
        if padding == "drop":
            per_clip = np.where(frames >= length, (frames - length) // stride + 1, 0)
        else:  # full windows, then one more while the clip's end is not yet covered
            covering = np.maximum(frames - length + stride - 1, 0) // stride + 1
            per_clip = np.where(frames > 0, np.minimum(covering, (frames + stride - 1) // stride), 0)
        self.clip = np.repeat(chosen, per_clip)
        first = np.repeat(np.cumsum(per_clip) - per_clip, per_clip)
        self.offset = (np.arange(len(self.clip)) - first) * stride
        self.start = np.repeat(begins, per_clip) + self.offset
        self.end = np.repeat(ends, per_clip)
        self.valid = np.minimum(self.end - self.start, length)

    def __len__(self) -> int:
        return len(self.clip)

    def __repr__(self) -> str:
        clips = len(np.unique(self.clip))
        return f"Windows({len(self)} of {self.length} frames, stride {self.stride}, {self.padding}; {clips} clips)"

    def rows(self, i: int) -> np.ndarray:
        """The dataset rows of window ``i``, the padded frames' rows being the clip's last."""
        return np.minimum(self.start[i] + np.arange(self.length), self.end[i] - 1)

    def read(self, array: np.ndarray, i: int) -> np.ndarray:
        """Window ``i`` of a whole-dataset ``array`` (``ds.positions``...) ``[length, ...]``: a view
        when it needs no padding, else a padded copy (``"edge"`` or ``"zero"``)."""
        start, valid = int(self.start[i]), int(self.valid[i])
        if valid == self.length:
            return array[start : start + self.length]
        out = array[self.rows(i)]
        if self.padding == "zero":
            out[valid:] = 0
        return out


def clip_windows(frames: np.ndarray, length: int, stride: int = 1) -> np.ndarray:
    """All full windows of one clip's array ``[F, ...]`` as ``[n, length, ...]``, a strided view
    of it (no copy: ``np.lib.stride_tricks``); ``n = (F - length) // stride + 1``, 0 when the clip
    is shorter than a window."""
    if length < 1 or stride < 1:
        raise ArgumentError(f"`length` and `stride` must be positive, got {length} and {stride}")
    if len(frames) < length:
        return np.empty((0, length, *frames.shape[1:]), dtype=frames.dtype)
    view = np.lib.stride_tricks.sliding_window_view(frames, length, axis=0)[::stride]
    return np.moveaxis(view, -1, 1)


__all__ = ["PADDING", "Windows", "clip_windows"]
