"""A batch's model-ready forms after its kernels (:mod:`.work`): the values of each clip's mirror
image, the skeleton's heading frame, the stored forms of :mod:`.derive` computed a chunk of clips
at a time, and the sums for the normalisation statistics (:mod:`.stats`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..body.body import Body
from ..body.conventions import ups_of
from ..errors import MocapError
from .derive import Options, derive, totals
from .heading import HeadingFrame

if TYPE_CHECKING:
    from .work import Group, Outcome


def mirror_values(values: dict, result, keep: tuple[str, ...]) -> dict:
    """A clip's mirror image's values (kind -> array) from its kernel ``result``: contacts are the
    clip's own, left for right (the image's feet are the clip's, swapped)."""
    if isinstance(result, Exception):  # arrays the clip's own kernel read: not expected to fail
        raise result
    positions, rotations, features, _, _ = result
    mirrored = {"positions": positions, "rotations": rotations}
    if "features" in keep:
        mirrored["features"] = features[0].astype(np.float32)
    if "contacts" in keep:
        mirrored["contacts"] = np.ascontiguousarray(values["contacts"][:, ::-1])
    return {kind: v for kind, v in mirrored.items() if kind in keep}


def heading_frames(group: Group, owners: list[Outcome], done: list, keep: tuple[str, ...], options: Options) -> list:
    """The heading frame of each clip and mirror image that succeeded, ``done`` (``owners``: the
    outcome each belongs to), read from its own frames alone, so that a clip's stored values do
    not depend on which clips share its batch: a HeadingFrame, None (no world positions, or no
    frame found where the kinds kept do not need one) or False (not found where they do: the
    clip failed). Each outcome gets its up axis."""
    if not done or done[0][1][0] is None:
        return [None] * len(done)
    skeleton = group.skeleton or group.headers[0].skeleton
    live = [k for k, outcome in enumerate(owners) if outcome.error is None]
    frames: list = [False] * len(done)  # False: its clip's frame was not found
    try:
        jmap = Body.of(skeleton).joint_map
        samples = [done[k][1][0] for k in live]
        ups = ups_of(jmap, [p[:: max(1, len(p) // SAMPLED_FRAMES)] for p in samples])
        by_up = {up: HeadingFrame.for_up(skeleton, up) for up in set(ups)}  # all that differs
    except MocapError as error:
        for k in live:
            if options.heading(keep):
                owners[k].error = f"no heading frame for --positions {options.positions}: {error}"
            frames[k] = False if options.heading(keep) else None
        return frames
    for k, up in zip(live, ups):
        frames[k] = by_up[up]
        owners[k].up = by_up[up].up
    return frames


# Frames of a clip its heading frame is read from (evenly spread).
SAMPLED_FRAMES = 64


def derive_group(group: Group, done: list, keep: tuple[str, ...], options: Options, frames: list) -> None:
    """The stored forms (:func:`.derive.derive`) of a hierarchy's clips and mirror images that
    succeeded, ``done`` ``(values, kernel result, frame time)`` with their heading ``frames``
    (:func:`heading_frames`; False: skipped), a chunk of clips of one frame at a time
    (:func:`chunks`); each clip's slices into its values."""
    root = int(np.flatnonzero(group.parents < 0)[0])
    kept = [(entry, frame) for entry, frame in zip(done, frames) if frame is not False]
    for part in chunks(kept, lambda item: _frames_of(item[0]), lambda item: _frame_key(item[1])):
        frame = part[0][1]
        part = [entry for entry, _ in part]
        positions = [r[0] for _, r, _ in part] if part[0][1][0] is not None else None
        counts = np.array([_frames_of(entry) for entry in part])
        starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
        stored = derive(
            keep,
            options,
            np.concatenate(positions) if positions is not None else None,
            np.concatenate([r[1] for _, r, _ in part]) if part[0][1][1] is not None else None,
            starts,
            np.repeat([t for _, _, t in part], counts),
            frame,
            root,
        )
        for (values, _, _), first, count in zip(part, starts, counts):
            values.update({kind: array[first : first + count] for kind, array in stored.items()})


def _frames_of(entry) -> int:
    result = entry[1]
    return len(result[0] if result[0] is not None else result[1])


def _frame_key(frame) -> tuple | None:
    """What tells two heading frames apart (None for none)."""
    return None if frame is None else (frame.turn.tobytes(), frame.hips, frame.pairs)


# Frames a chunk of clips holds when derived or mirrored together: arrays of a few MB, which the
# allocator reuses chunk after chunk; a whole batch's arrays at once (hundreds of MB) were fresh
# pages every time, and faulting them in took a third of the run (system time).
CHUNK_FRAMES = 8192


def chunks(items: list, frames, key=None) -> list[list]:
    """``items`` in consecutive runs of about :data:`CHUNK_FRAMES` frames (``frames(item)``) each,
    and of one ``key(item)`` each, when given."""
    out: list[list] = [[]]
    count = 0
    for item in items:
        if out[-1] and (count + frames(item) > CHUNK_FRAMES or (key is not None and key(item) != key(out[-1][0]))):
            out.append([])
            count = 0
        out[-1].append(item)
        count += frames(item)
    return out


def add_sums(finished: list, keep: tuple[str, ...]) -> None:
    """The float64 sums of rows and squares (:func:`.derive.totals`) per float kind kept of each
    clip and mirror image that succeeded, ``finished`` ``(outcome, values)`` in the batch's order,
    into its outcome's ``sums`` (the clip's, then its mirror image's): one kernel call a kind for
    the batch. Added clip by clip in the dataset's order (:mod:`.collect`), they make statistics
    that do not depend on how the clips were batched."""
    for outcome, _ in finished:
        outcome.sums = []
    for kind in keep:
        by_shape: dict[tuple, list] = {}  # one call per row shape (a batch may hold several skeletons)
        for outcome, values in finished:
            if kind in values and values[kind].dtype.kind == "f":
                by_shape.setdefault(values[kind].shape[1:], []).append((outcome, values[kind]))
        for images in by_shape.values():
            for (outcome, _), increment in zip(images, totals([v for _, v in images])):
                outcome.sums.append((kind, increment))


__all__ = ["CHUNK_FRAMES", "add_sums", "chunks", "derive_group", "heading_frames", "mirror_values"]
