"""The journal of a run (``OUT/.partial/journal.jsonl``): one JSON line per batch written,
appended after the batch's rows, so an interrupted run resumes from its last complete batch."""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

from .sources import Item


@dataclass
class JournalRecord:
    """One batch written: its number, the names of its ``items`` (clips and failures), the
    manifest records of its ``clips`` and ``failures``, the dataset's ``skeleton`` when this
    batch found it (its first parsed clip), the dataset's row count after the batch, the run's
    running sums for the normalisation statistics and the positions' ``up`` axis when this batch
    found it. On disk, a JSON object of these keys (``skeleton`` and ``up`` only when found)."""

    batch: int
    items: list[str]
    clips: list[dict] = field(default_factory=list)
    failures: list[dict] = field(default_factory=list)
    skeleton: dict | None = None
    rows: int = 0
    sums: dict | None = None  # the run's sums for the statistics after this batch: kind -> [rows, sums, squares]
    up: list | None = None  # the world positions' up axis, when this batch found it

    def to_json(self) -> dict:
        record: dict = {"batch": self.batch, "items": self.items, "clips": self.clips, "failures": self.failures}
        if self.skeleton is not None:
            record["skeleton"] = self.skeleton
        if self.up is not None:
            record["up"] = self.up
        if self.sums is not None:
            record["sums"] = self.sums
        record["rows"] = self.rows
        return record

    @classmethod
    def from_json(cls, record: dict) -> JournalRecord:
        return cls(
            record["batch"],
            record["items"],
            record["clips"],
            record["failures"],
            record.get("skeleton"),
            record["rows"],
            record.get("sums"),
            record.get("up"),
        )


def read_journal(path: Path) -> list[JournalRecord]:
    """Complete lines of the journal; a torn last line (a crash mid-append) is cut off."""
    if not path.exists():
        return []
    data = path.read_bytes()
    entries, good = [], 0
    for line in data.split(b"\n"):
        if not line.strip():
            good += len(line) + 1
            continue
        try:
            entries.append(json.loads(line))
        except (ValueError, RecursionError):  # a line cut short, or not ours
            break
        good += len(line) + 1
    if good < len(data):
        with open(path, "r+b") as handle:
            handle.truncate(min(good, len(data)))
    return [JournalRecord.from_json(entry) for entry in entries]


def append_record(path: Path, record: JournalRecord) -> None:
    """One journal line, appended in one write after the batch's rows: a run that is killed
    leaves the journal ending at its last complete batch. (Not fsynced: after a power cut the
    run may need redoing; the finished dataset is synced before its manifest appears.)"""
    with open(path, "ab") as handle:
        handle.write(json.dumps(record.to_json()).encode() + b"\n")


def not_done(items: Iterable[Item], done: Counter) -> Iterator[Item]:
    """The items an earlier run has not journaled: ``done`` counts the names journaled (a name
    twice when a second clip of that name failed as a duplicate)."""
    left = Counter(done)
    for item in items:
        if left[item.name] > 0:
            left[item.name] -= 1
            continue
        yield item


__all__ = ["JournalRecord", "append_record", "not_done", "read_journal"]
