"""Progress of long work on stderr: on a terminal, one line redrawn in place (count, rate, time
left); otherwise (a log file, CI) a plain line now and then; nothing when quiet."""

from __future__ import annotations

import sys
import time
from typing import TextIO


def _duration(seconds: float) -> str:
    seconds = int(round(seconds))
    return (
        f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"
        if seconds >= 3600
        else f"{seconds // 60}:{seconds % 60:02d}"
    )


def _amount(value: float, unit: str) -> str:
    if unit == "B":  # bytes: in MB, as the rest of the package reports them
        return f"{value / 1e6:.1f} MB"
    return f"{value:,.0f}{' ' + unit if unit else ''}"


class Progress:
    """``done`` of ``total`` units of work named ``what``, shown on ``stream``: a bar redrawn at
    most 10 times a second on a terminal, else one line every ``every`` seconds and at the end.
    ``total`` may be None (unknown: no bar, no time left). Use as a context manager or call
    :meth:`close`."""

    def __init__(
        self,
        total: float | None,
        what: str,
        unit: str = "",
        *,
        enabled: bool = True,
        stream: TextIO | None = None,
        every: float = 10.0,
    ):
        self.total, self.what, self.unit, self.every = total, what, unit, every
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = enabled
        self.terminal = enabled and getattr(self.stream, "isatty", lambda: False)()
        self.done, self.note = 0.0, ""
        self.start = self.shown = time.perf_counter()
        self.width = 0

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def update(self, amount: float = 1, note: str = "") -> None:
        """``amount`` more units done; ``note``: a short text shown after the counts."""
        self.done += amount
        self.note = note or self.note
        now = time.perf_counter()
        if self.enabled and now - self.shown >= (0.1 if self.terminal else self.every):
            self.shown = now
            self._show(now)

    def line(self, now: float | None = None) -> str:
        """The progress as text: what, a bar, done/total, rate, time left, note."""
        elapsed = max((now or time.perf_counter()) - self.start, 1e-9)
        rate = self.done / elapsed
        parts = [self.what]
        if self.total:
            fraction = min(self.done / self.total, 1.0)
            if self.terminal:
                parts.append("[" + "#" * int(fraction * 20) + "." * (20 - int(fraction * 20)) + "]")
            parts.append(f"{_amount(self.done, self.unit)}/{_amount(self.total, self.unit)} ({fraction:.0%})")
        else:
            parts.append(_amount(self.done, self.unit))
        parts.append(f"{_amount(rate, self.unit)}/s")
        if self.total and rate > 0 and self.done < self.total:
            parts.append(f"{_duration((self.total - self.done) / rate)} left")
        else:
            parts.append(f"{_duration(elapsed)} so far")
        if self.note:
            parts.append(self.note)
        return " ".join(parts)

    def _show(self, now: float) -> None:
        text = self.line(now)
        if self.terminal:
            self.stream.write("\r" + text.ljust(self.width))
            self.width = len(text)
        else:
            self.stream.write(text + "\n")
        self.stream.flush()

    def close(self) -> None:
        """Show the final state (on a terminal, end the redrawn line; elsewhere only after work
        long enough to have shown progress: a quick step stays silent in logs)."""
        if not self.enabled:
            return
        now = time.perf_counter()
        if self.terminal or now - self.start >= self.every:
            self._show(now)
        if self.terminal:
            self.stream.write("\n")
            self.stream.flush()
        self.enabled = False


def line_log(enabled: bool = True, stream: TextIO | None = None):
    """A ``log(line)`` callable for work that reports itself in lines (training): on a terminal,
    a line ending in ``\\r`` (a running count) is redrawn in place by the next; elsewhere only
    complete lines are written, ``\\r`` ones every ``10 s``."""
    state: dict[str, float] = {"width": 0, "shown": 0.0}

    def log(text: str) -> None:
        if not enabled:
            return
        out = stream if stream is not None else sys.stderr  # looked up now: tests and callers redirect it
        terminal = getattr(out, "isatty", lambda: False)()
        running = text.endswith("\r")
        text = text.rstrip("\r")
        if terminal:
            out.write("\r" + text.ljust(int(state["width"])) + ("" if running else "\n"))
            state["width"] = len(text) if running else 0
        elif not running or time.perf_counter() - state["shown"] >= 10.0:
            state["shown"] = time.perf_counter()
            out.write(text + "\n")
        out.flush()

    return log


__all__ = [
    "Progress",
    "line_log",
]
