"""Tokens of a BVH file: what a number is, and how a token is shown in an error message.

One number grammar for the whole file, header and MOTION block, in both backends: the Rust
MOTION parser's (``fast-float2``), ASCII decimal floats: an optional sign, digits with an optional
point (``5.`` and ``.5`` too), an optional exponent (``e-3``, ``E+07``). Python's ``float()`` also
takes ``1_000``, Arabic-Indic or full-width digits and surrounding blanks: none of these is a
number here. ``nan``, ``inf`` and ``infinity`` (any case, signed) are recognised, then refused as
not finite, like numbers beyond the float range (``1e999``). Tokens are separated by ASCII
blanks (space, tab, CR, form feed) and newlines, as in the Rust parser.
"""

from __future__ import annotations

import math
import re

# Each digit belongs to one part only: "[0-9]+\.?[0-9]*" made a long token of digits take
# quadratic time to refuse (a 1 MB token, minutes), backtracking over every split.
NUMBER_PATTERN = r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
NUMBER = re.compile(NUMBER_PATTERN)
NUMBER_BYTES = re.compile(NUMBER_PATTERN.encode("ascii"))
# What fast-float2 reads as NaN or infinity: refused as "not a finite number", not "not a number".
NOT_FINITE_BYTES = re.compile(rb"[+-]?(?:nan|inf(?:inity)?)", re.IGNORECASE)
BLANKS = " \t\r\x0c"  # blanks inside a line (Rust's u8::is_ascii_whitespace without '\n')


def finite_number(token: str) -> float | None:
    """The value of a number token of the grammar, or None (not a number, or not finite)."""
    if NUMBER.fullmatch(token) is None:
        return None
    value = float(token)
    return value if math.isfinite(value) else None


SHOWN_BYTES = 40  # of a token in an error message: a 1 MB token must not make a 1 MB message
_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u2028\u2029]")


def shown(token: str | bytes | bytearray | memoryview) -> str:
    """``token`` quoted for an error message, as the Rust parser's ``show`` writes it: its first
    40 bytes (UTF-8, undecodable bytes as U+FFFD), control characters and line separators
    escaped so the message stays one line, then ``... (N bytes)`` when it was cut."""
    raw = token.encode("utf-8", "surrogatepass") if isinstance(token, str) else memoryview(token).cast("B")
    text = bytes(raw[:SHOWN_BYTES]).decode("utf-8", "replace")
    text = _CONTROL.sub(lambda m: f"\\x{ord(m[0]):02x}" if ord(m[0]) < 0x100 else f"\\u{ord(m[0]):04x}", text)
    return f"'{text}'" if len(raw) <= SHOWN_BYTES else f"'{text}'... ({len(raw)} bytes)"


LISTED_NAMES = 40  # names listed in an error message, the rest counted


def listed(names) -> str:
    """Joint names for an error message: each :func:`shown`, the first :data:`LISTED_NAMES`, then
    how many more (a 10,000-joint rig must not make a megabyte line)."""
    names = list(names)
    out = ", ".join(shown(n)[1:-1] if len(n.encode()) <= SHOWN_BYTES else shown(n) for n in names[:LISTED_NAMES])
    return out if len(names) <= LISTED_NAMES else f"{out}, ... ({len(names) - LISTED_NAMES} more)"


__all__ = [
    "BLANKS",
    "LISTED_NAMES",
    "NOT_FINITE_BYTES",
    "NUMBER",
    "NUMBER_BYTES",
    "NUMBER_PATTERN",
    "SHOWN_BYTES",
    "finite_number",
    "listed",
    "shown",
]
