"""The joint tree of a BVH file's HIERARCHY from its text: its tokens and the tree they
describe, as plain Python values (no NumPy: a summary of a file, ``expressive-mocap info``, needs
no arrays; :mod:`.hierarchy` makes the :class:`~expressive_mocap.motion.Skeleton`). Every problem is a
:class:`~expressive_mocap.errors.BVHError` naming the file and the line."""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import cast

from .._utils.tokens import finite_number, shown
from ..errors import BVHError, MocapError
from ..rotations.orders import POSITION_CHANNELS, ROTATION_CHANNELS, canonical_channels

__all__ = [
    "COUNT_PATTERN",
    "MAX_CHANNELS",
    "MAX_JOINTS",
    "Sites",
    "Tree",
    "channel_summary",
    "parse_tree",
    "vertical_extent",
]

_TOKEN = re.compile(r"[{}]|[^ \t\r\n\x0c{}]+")  # ASCII blanks, as in the MOTION block (tokens.py)
_KEYWORDS = frozenset(["}", "OFFSET", "CHANNELS", "JOINT", "ROOT"])  # already in upper case
_CHANNEL_NAMES = frozenset(c.lower() for c in POSITION_CHANNELS + ROTATION_CHANNELS)

# Limits of the reader (docs/safety.md, "Limits"; the others are in header.py).
MAX_JOINTS = 10_000  # so also the depth of the hierarchy; read without recursion
MAX_CHANNELS = 6  # per joint: 3 positions and 3 rotations
COUNT_PATTERN = r"[0-9]{1,18}"  # ASCII digits only: str.isdigit() also takes '²'
_COUNT = re.compile(COUNT_PATTERN)
Sites = tuple[tuple[int, tuple[float, float, float]], ...]  # Skeleton.end_sites


@dataclass(frozen=True)
class Tree:
    """A hierarchy as the file gives it: the fields of a :class:`~expressive_mocap.motion.Skeleton`,
    in tuples (channel names canonical)."""

    names: tuple[str, ...]
    parents: tuple[int, ...]
    offsets: tuple[tuple[float, float, float], ...]
    channels: tuple[tuple[str, ...], ...]
    end_sites: Sites

    @property
    def n_joints(self) -> int:
        return len(self.names)

    @property
    def n_channels(self) -> int:
        return sum(len(c) for c in self.channels)


def channel_summary(channels: Sequence[tuple[str, ...]]) -> str:
    """A one-line summary of joints' channel lists, e.g. ``22 joints x 6 (Xposition ... Yrotation)``."""
    layouts: dict[tuple[str, ...], int] = {}
    for cs in channels:
        layouts[cs] = layouts.get(cs, 0) + 1
    return "; ".join(
        f"{n} joint{'s' if n > 1 else ''} x {len(cs)} ({' '.join(cs) or 'none'})" for cs, n in layouts.items()
    )


def vertical_extent(parents: Sequence[int], heights: Sequence[float], end_sites: Sites) -> float:
    """The rest pose's Y extent, End Sites included: ``heights`` are the joints' offsets along Y
    (parents first, as in a BVH file)."""
    y: list[float] = []
    for parent, height in zip(parents, heights):
        y.append(height if parent < 0 else y[parent] + height)
    y += [y[joint] + offset[1] for joint, offset in end_sites]
    return max(y) - min(y)


class _Tokens:
    """Header tokens with their line numbers, consumed front to back."""

    def __init__(self, text: str, name: str):
        self.name = name
        self.words: list[str] = []
        self.lines: list[int] = []
        for number, line in enumerate(text.split("\n"), 1):
            found = _TOKEN.findall(line)
            self.words += found
            self.lines += [number] * len(found)
        self.pos = 0
        self.last_line = text.count("\n") + 1

    def error(self, line: int | None, reason: str) -> BVHError:
        return BVHError(self.name, line, reason)

    def done(self) -> bool:
        return self.pos >= len(self.words)

    def next(self, expected: str) -> tuple[str, int]:
        pos = self.pos
        if pos >= len(self.words):
            raise self.error(self.last_line, f"unexpected end of the header: expected {expected}")
        self.pos = pos + 1
        return self.words[pos], self.lines[pos]

    def expect(self, word: str) -> int:
        token, line = self.next(repr(word))
        if token != word and token.lower() != word.lower():
            raise self.error(line, f"expected {word!r}, found {shown(token)}")
        return line

    def numbers(self, count: int, what: str) -> list[float]:
        start = self.pos
        if start + count > len(self.words):
            self.pos = len(self.words)
            self.next(what)  # raises the end-of-header error
        self.pos = start + count
        values = [finite_number(w) for w in self.words[start : start + count]]
        for k, value in enumerate(values, start):
            if value is None:
                raise self.error(self.lines[k], f"expected {what} (a finite number), found {shown(self.words[k])}")
        return cast(list[float], values)  # no None left

    def name_on_line(self, keyword_line: int, what: str) -> str:
        """The rest of the keyword's line up to '{' (names may contain spaces or ':')."""
        start = pos = self.pos
        words, lines = self.words, self.lines
        while pos < len(words) and lines[pos] == keyword_line and words[pos] != "{":
            pos += 1
        if pos == start:
            raise self.error(keyword_line, f"expected the name of the {what}")
        self.pos = pos
        return words[start] if pos == start + 1 else " ".join(words[start:pos])


def parse_tree(text: str, name: str) -> tuple[Tree, list[int]]:
    """The joint tree of the hierarchy ``text`` (HIERARCHY up to MOTION) of the file ``name``, and
    the owner of each OFFSET in file order (joint j, or -1 - k for End Site k)."""
    # One function, longer than most: a single pass over the tokens with an explicit stack (no
    # recursion, for 10,000-deep chains); each keyword's branch is short and shares that state.
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float] | None] = []
    channels: list[tuple[str, ...] | None] = []
    end_sites: list[tuple[int, list[float] | None]] = []
    opened_at: list[int] = []  # line of each joint's '{', for unbalanced-brace errors
    offset_owners: list[int] = []

    tokens = _Tokens(text, name)
    tokens.expect("HIERARCHY")
    root_line = tokens.expect("ROOT")
    # Stack of open blocks: a joint index, or -1 - (index into end_sites) for an End Site.
    stack: list[int] = []

    first_line: dict[str, int] = {}  # of each joint name

    def open_joint(keyword_line: int, parent: int) -> None:
        if len(names) == MAX_JOINTS:
            raise tokens.error(
                keyword_line, f"more than {MAX_JOINTS} joints: the reader's limit (see docs/safety.md, Limits)"
            )
        name = tokens.name_on_line(keyword_line, "joint")
        if name in first_line:
            raise tokens.error(
                keyword_line, f"joint name {shown(name)} appears more than once (first at line {first_line[name]})"
            )
        first_line[name] = keyword_line
        names.append(name)
        parents.append(parent)
        offsets.append(None)
        channels.append(None)
        opened_at.append(tokens.expect("{"))
        stack.append(len(names) - 1)

    open_joint(root_line, -1)
    while stack:
        if tokens.done():
            joint = next(j for j in reversed(stack) if j >= 0)
            raise tokens.error(
                tokens.last_line,
                f"unbalanced braces: the '{{' of joint {shown(names[joint])} at line {opened_at[joint]} "
                "is never closed",
            )
        token, line = tokens.next("'}'")
        top = stack[-1]
        word = token if token in _KEYWORDS else token.upper()
        if word == "}":
            if top >= 0 and offsets[top] is None:
                raise tokens.error(line, f"joint {shown(names[top])} has no OFFSET")
            if top < 0 and end_sites[-1 - top][1] is None:
                raise tokens.error(line, "End Site has no OFFSET")
            stack.pop()
        elif top < 0:
            if word != "OFFSET" or end_sites[-1 - top][1] is not None:
                raise tokens.error(line, f"expected OFFSET or '}}' in an End Site, found {shown(token)}")
            end_sites[-1 - top] = (end_sites[-1 - top][0], tokens.numbers(3, "an OFFSET value"))
            offset_owners.append(top)
        elif word == "OFFSET":
            if offsets[top] is not None:
                raise tokens.error(line, f"joint {shown(names[top])} has a second OFFSET")
            offsets[top] = tokens.numbers(3, "an OFFSET value")
            offset_owners.append(top)
        elif word == "CHANNELS":
            if channels[top] is not None:
                raise tokens.error(line, f"joint {shown(names[top])} has a second CHANNELS line")
            count_token, count_line = tokens.next("the number of channels")
            if not _COUNT.fullmatch(count_token) or int(count_token) > MAX_CHANNELS:
                raise tokens.error(
                    count_line, f"expected a channel count from 0 to {MAX_CHANNELS}, found {shown(count_token)}"
                )
            listed = tuple(tokens.words[tokens.pos : tokens.pos + int(count_token)])
            if len(listed) < int(count_token):
                tokens.pos = len(tokens.words)
                tokens.next("a channel name")  # raises the end-of-header error
            tokens.pos += len(listed)
            try:
                canonical = canonical_channels(listed)
            except MocapError as error:
                bad = next(k for k, n in enumerate(listed) if n.lower() not in _CHANNEL_NAMES)
                raise tokens.error(tokens.lines[tokens.pos - len(listed) + bad], str(error)) from None
            channels[top] = canonical
            if len(set(canonical)) != len(listed):  # canonical names: "Xrotation" and "XROTATION" are one
                raise tokens.error(line, f"joint {shown(names[top])} lists a channel twice: {' '.join(listed)}")
        elif word == "JOINT":
            open_joint(line, top)
        elif word == "END":
            tokens.expect("Site")
            end_sites.append((top, None))
            tokens.expect("{")
            stack.append(-len(end_sites))
        elif word == "ROOT":
            raise tokens.error(line, "several ROOT hierarchies in one file are not supported (a ROOT inside a joint)")
        else:
            raise tokens.error(line, f"expected OFFSET, CHANNELS, JOINT, End Site or '}}', found {shown(token)}")

    if not tokens.done():
        token, line = tokens.next("MOTION")
        if token.upper() == "ROOT":
            raise tokens.error(
                line, "several ROOT hierarchies in one file are not supported: only the first ROOT can be read"
            )
        if token == "}":
            raise tokens.error(line, "unbalanced braces: this '}' closes nothing")
        raise tokens.error(line, f"expected MOTION after the hierarchy, found {shown(token)}")
    tree = Tree(
        names=tuple(names),
        parents=tuple(parents),
        offsets=tuple(cast(tuple[float, float, float], tuple(off or ())) for off in offsets),
        channels=tuple(c or () for c in channels),
        end_sites=cast(Sites, tuple((j, tuple(off or ())) for j, off in end_sites)),  # every End Site has its OFFSET
    )
    return tree, offset_owners
