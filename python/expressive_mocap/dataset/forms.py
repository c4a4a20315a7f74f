"""A batch's model-ready forms after its kernels (:mod:`.work`): the values of each clip's mirror
image, the skeleton's heading frame, the stored forms of :mod:`.derive` computed a chunk of clips
at a time, and the sums for the normalisation statistics (:mod:`.stats`)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from ..errors import MocapError
from ..heading import HeadingFrame
from .derive import Options, derive, totals

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


def heading_frame(group: Group, outcomes: list[Outcome], done: list, keep: tuple[str, ...], options: Options):
    """The heading frame of a hierarchy whose clips that succeeded are ``done`` (None: no world
    positions, or no frame found where the kinds kept do not need one; False: not found where
    they do, and the clips failed), its up axis in each outcome."""
    if not done or done[0][1][0] is None:
        return None
    sample = np.concatenate([r[0][:: max(1, len(r[0]) // 8)] for _, r, _ in done[:64]])
    try:
        frame = HeadingFrame.of(group.skeleton or group.headers[0].skeleton, sample)
    except MocapError as error:
        if not options.heading(keep):
            return None
        for outcome in outcomes:
            if outcome.error is None:
                outcome.error = f"no heading frame for --positions {options.positions}: {error}"
        return False
    for outcome in outcomes:
        outcome.up = frame.up
    return frame


def derive_group(group: Group, done: list, keep: tuple[str, ...], options: Options, frame) -> None:
    """The stored forms (:func:`.derive.derive`) of a hierarchy's clips and mirror images that
    succeeded, ``done`` ``(values, kernel result, frame time)``, a chunk of clips at a time
    (:func:`chunks`); each clip's slices into its values."""
    root = int(np.flatnonzero(group.parents < 0)[0])
    for part in chunks(done, lambda entry: len(entry[1][0] if entry[1][0] is not None else entry[1][1])):
        positions = [r[0] for _, r, _ in part] if part[0][1][0] is not None else None
        frames = np.array([len(r[0] if r[0] is not None else r[1]) for _, r, _ in part])
        starts = np.concatenate([[0], np.cumsum(frames)[:-1]])
        stored = derive(
            keep,
            options,
            np.concatenate(positions) if positions is not None else None,
            np.concatenate([r[1] for _, r, _ in part]) if part[0][1][1] is not None else None,
            starts,
            np.repeat([t for _, _, t in part], frames),
            frame,
            root,
        )
        for (values, _, _), first, count in zip(part, starts, frames):
            values.update({kind: array[first : first + count] for kind, array in stored.items()})


# Frames a chunk of clips holds when derived or mirrored together: arrays of a few MB, which the
# allocator reuses chunk after chunk; a whole batch's arrays at once (hundreds of MB) were fresh
# pages every time, and faulting them in took a third of the run (system time).
CHUNK_FRAMES = 8192


def chunks(items: list, frames) -> list[list]:
    """``items`` in consecutive runs of about :data:`CHUNK_FRAMES` frames (``frames(item)``) each."""
    out: list[list] = [[]]
    count = 0
    for item in items:
        if out[-1] and count + frames(item) > CHUNK_FRAMES:
            out.append([])
            count = 0
        out[-1].append(item)
        count += frames(item)
    return out


def add_sums(finished: list, keep: tuple[str, ...]) -> None:
    """The float64 sums of rows and squares (:func:`.derive.totals`) per float kind kept over each
    hierarchy's clips and mirror images that succeeded, ``finished`` ``(outcome, [values])``,
    into that outcome's ``sums``: one reduction a kind over a group, not one a clip."""
    for carrier, done in finished:
        if carrier.error is not None:  # the group failed after its kernel (no heading frame)
            continue
        for kind in keep:
            arrays = [values[kind] for values in done if kind in values and values[kind].dtype.kind == "f"]
            if arrays:
                carrier.sums[kind] = totals(arrays)


__all__ = ["CHUNK_FRAMES", "add_sums", "chunks", "derive_group", "heading_frame", "mirror_values"]
