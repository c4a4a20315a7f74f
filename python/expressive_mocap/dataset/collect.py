"""A batch's outcomes, in order, into its journal record (clips and failures) and the rows to
append per kind: one dataset holds one skeleton, in one unit, and each clip name once."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .format import MIRRORED
from .journal import JournalRecord
from .sources import Item
from .work import Outcome

# People differ in size by less than this factor; units (cm/inch 2.54, m/cm 100) by more.
SAME_UNITS_RATIO = 2.0


@dataclass
class Collected:
    """A batch collected: the arrays to append per kind, the row count after the batch and the
    dataset's skeleton (the manifest's record: names, parents, bone_length; None until a clip's
    header was read)."""

    arrays: dict[str, list[np.ndarray]]
    rows: int
    skeleton: dict | None
    # (kind, (rows, sums of rows, sums of squares)) of each stored clip and mirror image, in order
    sums: list[tuple[str, tuple]] = field(default_factory=list)
    up: list | None = None  # the up axis of the dataset's world positions, when a clip found it


def collect(
    batch: list[Item],
    outcomes: list[Outcome],
    skeleton: dict | None,
    keep,
    record: JournalRecord,
    rows: int,
    taken: set,
    majority: tuple | None = None,
) -> Collected:
    """The batch's outcomes in order: clips and failures into ``record`` (a clip of another
    skeleton than the dataset's is a failure, its record naming its own skeleton; so is a clip
    whose name ``taken``, the names taken so far, already holds), their arrays per kind; a clip's
    mirror image right after it, as a clip of its own (``{name}@mirrored``, ``mirror_of`` its
    name). The dataset's skeleton is the first parsed clip's of the hierarchy ``majority`` (names,
    parents: the one most clips share, :meth:`.census.Census.majority`), or of any when None."""
    arrays: dict[str, list[np.ndarray]] = {k: [] for k in keep}
    increments: list[tuple[str, tuple]] = []
    up = None
    for item, outcome in zip(batch, outcomes):
        shape, error = outcome.skeleton, outcome.error
        if item.name in taken:
            shape, error = (
                None,
                (
                    f"{item.source}: a clip named {item.name!r} is already in the dataset "
                    "(names are paths below the source without .bvh; one dataset holds each name once)"
                ),
            )
        taken.add(item.name)
        image = f"{item.name}{MIRRORED}"
        if outcome.mirrored is not None and error is None and image in taken:
            error = f"{item.source}: its mirror image's name {image!r} is already in the dataset"
        other = None  # a clip of another hierarchy than the dataset's: its own, for its failure record
        if shape is not None:
            names, parents = list(shape[0]), list(shape[1])
            expected = skeleton or (
                None if majority is None else {"names": list(majority[0]), "parents": list(majority[1])}
            )
            if expected is None or (skeleton is None and _same(shape, expected)):
                skeleton = record.skeleton = {"names": names, "parents": parents, "bone_length": outcome.bone_length}
            elif not _same(shape, expected):
                other = {"joints": len(names), "root": names[0] if names else None}
                error = _skeleton_error(item, names, parents, expected)
            elif error is None:
                error = _units_error(item, outcome.bone_length, expected)
        if error is not None:
            record.failures.append({"name": item.name, "source": item.source, "error": error})
            if other is not None:
                record.failures[-1]["skeleton"] = other
            continue
        increments += outcome.sums  # the statistics' sums, clip by clip in the dataset's order
        up = up or outcome.up
        if outcome.mirrored is not None:
            taken.add(image)
        images = [(item.name, outcome.values)]
        if outcome.mirrored is not None:
            images.append((f"{item.name}{MIRRORED}", outcome.mirrored))
        for name, values in images:
            for kind in keep:
                arrays[kind].append(values[kind])
            record.clips.append({"name": name, "source": item.source, "frames": outcome.frames,
                                 "fps": outcome.fps, "frame_time": outcome.frame_time, "start": rows})  # fmt: skip
            if name != item.name:
                record.clips[-1]["mirror_of"] = item.name
            if outcome.source_fps is not None:
                record.clips[-1]["source_fps"] = outcome.source_fps
            if outcome.source_skeleton is not None:
                record.clips[-1]["source_skeleton"] = outcome.source_skeleton
            rows += outcome.frames
    return Collected(arrays, rows, skeleton, increments, None if up is None else list(up))


def _same(shape: tuple, skeleton: dict | None) -> bool:
    """Whether joint names and parents ``shape`` are the dataset's ``skeleton``'s."""
    return skeleton is not None and list(shape[0]) == skeleton["names"] and list(shape[1]) == skeleton["parents"]


def _skeleton_error(item: Item, names: list, parents: list, skeleton: dict) -> str:
    """The error of a clip of another hierarchy (joint ``names``, ``parents``) than the dataset's
    ``skeleton``. What to do about it (``--canonical``) the run's summary says once, with the count
    of such clips (:class:`.summary.Summary`), not every failure."""
    return f"{item.source}: another skeleton than the dataset's: {_difference(names, parents, skeleton)}"


def _difference(names: list, parents: list, skeleton: dict) -> str:
    """How a hierarchy differs from the dataset's, in a few words: joint counts, the first joint
    that differs (its name or its parent)."""
    theirs, their_parents = skeleton["names"], skeleton["parents"]
    counts = f"{len(names)} joints against {len(theirs)}"
    for j, (a, b) in enumerate(zip(names, theirs)):
        if a != b:
            return f"{counts}; joint {j} is {a!r} where the dataset has {b!r}"
        if parents[j] != their_parents[j]:
            return f"{counts}; joint {j} ({a!r}) hangs from joint {parents[j]}, the dataset's from {their_parents[j]}"
    return f"{counts}; the first {min(len(names), len(theirs))} joints agree"


def _units_error(item: Item, length: float, skeleton: dict) -> str | None:
    """Why a clip of the dataset's skeleton is in other units than its first clip, or None:
    positions in two units in one array would be silently wrong."""
    reference = skeleton.get("bone_length")
    if not reference or not length:
        return None
    ratio = length / reference
    if 1 / SAME_UNITS_RATIO <= ratio <= SAME_UNITS_RATIO:
        return None
    return (
        f"{item.source}: its bones are {ratio:.3g}x as long as the dataset's "
        f"(summed {length:.4g} against {reference:.4g}): "
        "other units? One dataset holds one unit: rescale it first (expressive-mocap convert --scale)"
    )


__all__ = ["SAME_UNITS_RATIO", "Collected", "collect"]
