"""The state of a dataset folder before a run writes it: whether it is ours to write, and
removing a finished dataset or an unfinished run by the format's fixed file names only."""

from __future__ import annotations

import os
from pathlib import Path

from ..errors import DatasetError
from .format import LOCK, MANIFEST, OWN_FILES, PARTIAL, PARTIAL_FILES, RUN, read_manifest


def finished_manifest(out: Path) -> dict | None:
    """The manifest of the finished dataset in ``out``, None when there is none, after refusing a
    folder that is not ours to write: not a folder, a ``.partial`` that is not a real folder
    (a link would make us write elsewhere), or a non-empty folder that holds neither a dataset
    nor an unfinished run (the user's own files are never replaced).

    Another run may be changing ``out`` meanwhile (this is called before the lock is taken, and
    again under it): the folder is judged from one listing of its names, and a file that goes
    while it is read means a run at work, left to the lock to name."""
    if not out.exists():
        return None
    if not out.is_dir():
        raise DatasetError(f"{out}: not a folder (a dataset is a folder)")
    try:
        return _judged(out, set(os.listdir(out)))
    except FileNotFoundError:  # a run renaming its files into place right now
        return None


def _judged(out: Path, names: set[str]) -> dict | None:
    """:func:`finished_manifest` of ``out`` whose names were ``names`` when listed."""
    partial = out / PARTIAL
    if PARTIAL in names and (partial.is_symlink() or (partial.exists() and not partial.is_dir())):
        raise DatasetError(f"{partial}: not a folder of ours (a link or a file); move it away")
    if MANIFEST in names:
        return read_manifest(out / MANIFEST)
    if PARTIAL in names:
        # Without run.json: a run of ours starting (another process making it right now) or
        # killed as it started, if it holds only our names; anything else is not ours.
        if not (partial / RUN).is_file() and not all(_ours(name) for name in os.listdir(partial)):
            raise DatasetError(f"{partial} is not an unfinished run of ours (no {RUN}); move it away")
        if not (partial / MANIFEST).exists():  # a run not yet moving its files into place
            clash = sorted(OWN_FILES & set(os.listdir(out)))
            if clash:
                raise DatasetError(
                    f"{out} holds {', '.join(clash)} beside an unfinished run, without a manifest: "
                    "not ours to replace; move them away"
                )
        return None
    foreign = sorted(names - {LOCK})
    if foreign:
        shown = ", ".join(foreign[:5]) + (f" and {len(foreign) - 5} more" if len(foreign) > 5 else "")
        raise DatasetError(f"{out} is not empty ({shown}) and holds no dataset: choose a new or empty folder")
    return None


def remove_dataset(out: Path) -> None:
    """Unmake the finished dataset in ``out`` (its manifest already read and checked): the
    manifest first, so no reader sees old and new files mixed, then its files by their fixed
    names; anything else in the folder stays."""
    (out / MANIFEST).unlink()
    for name in sorted(OWN_FILES - {MANIFEST}):
        (out / name).unlink(missing_ok=True)


def remove_partial(out: Path) -> None:
    """Delete ``out/.partial``: the files a run writes there, by their fixed names (and the
    temporaries of its atomic writes), then the folder; a file of someone else's stops it."""
    partial = out / PARTIAL
    if not partial.is_dir() or partial.is_symlink():
        return
    for name in os.listdir(partial):
        if _ours(name):
            (partial / name).unlink(missing_ok=True)
    try:
        partial.rmdir()
    except OSError:
        raise DatasetError(
            f"{partial} holds files this package did not write ({', '.join(sorted(os.listdir(partial))[:5])}); "
            "left in place: move them away"
        ) from None


def _ours(name: str) -> bool:
    """Whether a file in ``.partial`` is one a run writes: a fixed name, or an atomic write's temporary."""
    temporary = name.endswith(".tmp") and any(name.startswith(f".{own}.") for own in PARTIAL_FILES)
    return name in PARTIAL_FILES or temporary


__all__ = ["finished_manifest", "remove_dataset", "remove_partial"]
