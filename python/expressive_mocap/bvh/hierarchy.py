"""The skeleton of a BVH file's HIERARCHY (its tree: :mod:`.tree`), and a cache of the
hierarchies already read (archives repeat a few). Every problem is a
:class:`~expressive_mocap.errors.BVHError` naming the file and the line."""

from __future__ import annotations

import re

import numpy as np

from .._utils.tokens import NUMBER_PATTERN
from ..errors import BVHError, MocapError
from ..motion import Skeleton
from .tree import MAX_CHANNELS, MAX_JOINTS, parse_tree

__all__ = ["MAX_CHANNELS", "MAX_JOINTS", "read_hierarchy"]

# Archives repeat a few hierarchies, some with different numbers (Bandai-Namco's Hips offset
# changes from clip to clip). A hierarchy is cached under its exact text, and under its text with
# the OFFSET numbers cut out: a file of a known shape then only converts its numbers. Anything
# unusual takes the full parse, whose errors name the line.
# A number is cut out only whole: "0}" stays in the shape (found by fuzz_bvh.py: "OFFSET 0 0 0}"
# cached a shape that a later "OFFSET 0 0 0" without its brace matched, and was read).
# Only tokens of the number grammar are cut out: anything else takes the full parse and its error.
_OFFSET_NUMBERS = re.compile(
    rf"(?<=OFFSET)[ \t]+({NUMBER_PATTERN})[ \t]+({NUMBER_PATTERN})[ \t]+({NUMBER_PATTERN})(?=[ \t]*\r*$)", re.MULTILINE
)
_SHAPES: dict[tuple[str, ...], tuple[Skeleton, np.ndarray, np.ndarray]] = {}
_HIERARCHIES: dict[str, Skeleton] = {}
_MAX_SHAPES = 64


def read_hierarchy(text: str, name: str) -> Skeleton:
    """The skeleton of the hierarchy ``text`` (HIERARCHY up to MOTION) of the file ``name``."""
    exact = _HIERARCHIES.get(text)
    if exact is not None:
        return exact
    parts = _OFFSET_NUMBERS.split(text)
    shape = tuple(parts[0::4])
    cached = _SHAPES.get(shape)
    if cached is not None:
        template, joint_rows, site_rows = cached
        try:
            offsets = np.array([parts[1::4], parts[2::4], parts[3::4]], dtype=np.float64).T
        except ValueError:
            offsets = None
        if offsets is not None and np.isfinite(offsets).all():
            return _remember(text, template.with_offsets(offsets[joint_rows], offsets[site_rows]))
    tree, owners = parse_tree(text, name)
    try:
        skeleton = Skeleton(tree.names, np.array(tree.parents), np.array(tree.offsets), tree.channels, tree.end_sites)
    except MocapError as error:  # the tree's checks should catch everything first, with a line
        raise BVHError(name, None, str(error)) from None
    if len(owners) == len(shape) - 1:  # every OFFSET was cut out: the shape says it all
        owner = np.array(owners)
        joint_rows, site_rows = np.flatnonzero(owner >= 0), np.flatnonzero(owner < 0)
        if len(_SHAPES) >= _MAX_SHAPES:
            _SHAPES.clear()
        _SHAPES[shape] = (
            skeleton,
            joint_rows[np.argsort(owner[joint_rows])],
            site_rows[np.argsort(-1 - owner[site_rows])],
        )
    return _remember(text, skeleton)


def _remember(text: str, skeleton: Skeleton) -> Skeleton:
    """Keep the skeleton of this exact hierarchy text: many clips share one (skeletons are immutable)."""
    if len(_HIERARCHIES) >= _MAX_SHAPES:
        _HIERARCHIES.clear()
    _HIERARCHIES[text] = skeleton
    return skeleton
