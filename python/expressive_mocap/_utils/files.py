"""Files: reading inputs safely (regular files of a bounded size only) and writing outputs safely
(a complete file appears at the destination, or nothing does). Model files: :mod:`.model_files`."""

from __future__ import annotations

import errno
import os
import stat
import sys
from pathlib import Path

from ..errors import MocapError

# The largest BVH file or archive member read (docs/safety.md, "Limits"): 512 MiB of text is over half an
# hour of a 60-joint skeleton at 120 fps, and decodes to about 1.2 GB of arrays. Checked before
# reading, so a 1 GiB member of a 1 MB zip, or a link to /dev/zero, is refused without reading it.
MAX_INPUT_BYTES = 512 << 20


def file_kind(mode: int) -> str:
    """What a file of this ``st_mode`` is, in words, for errors ("a FIFO", "a folder", ...)."""
    for test, name in (
        (stat.S_ISREG, "a regular file"),
        (stat.S_ISLNK, "a symlink"),
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return name
    return "not a regular file"


def open_input(path: str | os.PathLike, limit: int = MAX_INPUT_BYTES):
    """A binary file object of the regular file at ``path`` (symlinks followed), checked on the
    descriptor that will be read, so nothing can be swapped in between: a FIFO, device, socket
    or folder is refused without blocking (opening a FIFO to read waits for a writer, and
    /dev/zero never ends), and so is a file larger than ``limit`` bytes. Refusals are OSErrors
    with errno and a ``strerror`` that says what was found, like any other unreadable file."""
    handle, _ = _open_checked(path, limit)
    try:
        os.set_blocking(handle, True)
        return open(handle, "rb")  # the caller closes it
    except BaseException:
        os.close(handle)
        raise


def read_beginning(path: str | os.PathLike, count: int, limit: int = MAX_INPUT_BYTES) -> tuple[bytes, int]:
    """The first ``count`` bytes of the regular file at ``path`` (all of it if shorter) and its
    size, checked as :func:`open_input` checks it. Four system calls: readers of archives call
    this for every file from a thread of their own, and each call lets the other threads take
    the GIL in between (through a buffered file object, ten calls and twice the time)."""
    handle, size = _open_checked(path, limit)
    try:
        parts, read = [], 0
        while read < count:  # a regular file reads short only at its end (or on some network file systems)
            part = os.read(handle, count - read)
            if not part:
                break
            parts.append(part)
            read += len(part)
        return (parts[0] if len(parts) == 1 else b"".join(parts)), size
    finally:
        os.close(handle)


def _open_checked(path: str | os.PathLike, limit: int) -> tuple[int, int]:
    """The descriptor (non-blocking, the caller closes it) and size of the regular file at
    ``path``, or the OSError saying why not (see :func:`open_input`)."""
    try:
        handle = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as error:  # a socket cannot be opened at all (ENXIO): say what it is
        mode = _stat_mode(path)
        if mode is None or stat.S_ISREG(mode) or stat.S_ISDIR(mode):
            raise
        raise _not_regular(error.errno or errno.EINVAL, mode, path) from None
    try:
        info = os.fstat(handle)
        if not stat.S_ISREG(info.st_mode):
            raise _not_regular(errno.EISDIR if stat.S_ISDIR(info.st_mode) else errno.EINVAL, info.st_mode, path)
        if info.st_size > limit:
            raise too_large(limit, path, info.st_size)
        return handle, info.st_size
    except BaseException:
        os.close(handle)
        raise


def _not_regular(code: int, mode: int, path) -> OSError:
    return OSError(code, f"{file_kind(mode)}, not a regular file: only regular files are read", str(path))


def _stat_mode(path) -> int | None:
    try:
        return os.stat(path).st_mode
    except OSError:
        return None


def read_input(path: str | os.PathLike, limit: int = MAX_INPUT_BYTES) -> bytes:
    """The bytes of the regular file at ``path`` (see :func:`open_input`), at most ``limit`` of
    them: a file that grows past the bound while it is read is refused too."""
    with open_input(path, limit) as handle:
        return read_at_most(handle, limit, path, size=os.fstat(handle.fileno()).st_size)


def read_at_most(handle, limit: int, name, size: int | None = None) -> bytes:
    """The bytes of an open binary ``handle`` (a file, an archive member), at most ``limit``:
    one byte past the bound is read, no more, to refuse a longer one with :func:`too_large`.
    ``size``: what it should hold, when known: read(n) of a file reserves n bytes up front, so
    that plus one byte is asked for (to see it grow), and on towards the bound only if it did."""
    data = handle.read(limit + 1 if size is None else min(size, limit) + 1)
    if size is not None and size < len(data) <= limit:  # it grew while read
        data += handle.read(limit + 1 - len(data))
    if len(data) > limit:
        raise too_large(limit, name)
    return data


# Output names that mean the process's standard output: written through as they come, never
# renamed over (os.replace on /dev/stdout would replace the link in /dev).
STANDARD_OUTPUT = ("-", "/dev/stdout")


def is_standard_output(path) -> bool:
    """Whether ``path`` names standard output (``-`` or ``/dev/stdout``) rather than a file."""
    return isinstance(path, (str, os.PathLike)) and os.fspath(path) in STANDARD_OUTPUT


def output_target(path: str | os.PathLike) -> Path:
    """The file that writing to ``path`` replaces, checked before any work: ``path`` itself when it
    is missing or a regular file; for a symlink to a regular file, that file (written through the
    link, so the link survives). Anything else (a folder, a FIFO, a socket, a character or block
    device such as /dev/null, a symlink to one of those, to nothing or to itself) is a one-line
    :class:`MocapError` naming ``path`` and what it is: an output replaces a regular file or
    creates one, and never turns some other kind of file into one."""
    path = Path(path)
    try:
        info = os.lstat(path)
    except (FileNotFoundError, NotADirectoryError):
        return path  # a new file: its folder is checked where it is written
    except OSError as error:
        raise MocapError(f"cannot write {path}: {error.strerror or error}") from None
    target = path
    if stat.S_ISLNK(info.st_mode):
        target = Path(os.path.realpath(path))
        try:
            info = os.lstat(target)
        except OSError:
            raise MocapError(f"cannot write {path}: a symlink to {target}, which does not exist") from None
        if stat.S_ISLNK(info.st_mode):
            raise MocapError(f"cannot write {path}: a symlink that leads back to itself")
    if not stat.S_ISREG(info.st_mode):
        what = file_kind(info.st_mode) if target == path else f"a symlink to {file_kind(info.st_mode)}, {target}"
        raise MocapError(
            f"cannot write {path}: it is {what}, not a regular file (outputs replace regular files "
            "only; '-' writes to standard output)"
        )
    return target


def too_large(limit: int, name, size: int | None = None) -> OSError:
    """The OSError (EFBIG) of an input over ``limit`` bytes (of ``size`` bytes, when known)."""
    found = "more" if size is None else f"{size:,} bytes, more"
    return OSError(errno.EFBIG, f"{found} than the {limit:,} bytes read at most", str(name))


def atomic_write(path: str | os.PathLike, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file in the same folder and a rename; see
    :func:`atomic_write_all`. ``-`` or ``/dev/stdout`` write ``data`` to standard output as it is."""
    atomic_write_all({path: data})


def atomic_write_all(files: dict) -> None:
    """Write files that belong together (``{path: bytes}``): every one to a temporary file in its
    folder first, then all renamed into place; if any cannot be written, none appears and every
    destination is untouched. Every destination is checked first (:func:`output_target`): a
    regular file is replaced, a symlink to one has its target replaced, and anything else is
    refused. ``-`` and ``/dev/stdout`` are standard output, written directly (not atomically: a
    reader of the stream sees what came before an error). Errors are :class:`MocapError` naming
    the path, e.g. ``cannot write out.bvh: No space left on device``."""
    streams = [data for path, data in files.items() if is_standard_output(path)]
    targets = {Path(path): output_target(path) for path in files if not is_standard_output(path)}
    temporaries: list[tuple[str, Path, Path]] = []
    try:
        for path, data in files.items():
            if not is_standard_output(path):
                temporaries.append((_temporary(Path(path), targets[Path(path)], data), Path(path), targets[Path(path)]))
        for temporary, path, target in temporaries:
            output_target(path)  # again: nothing may have been swapped in meanwhile
            try:
                os.replace(temporary, target)
            except OSError as error:
                raise MocapError(f"cannot write {path}: {error.strerror or error}") from None
    except BaseException:
        for temporary, _, _ in temporaries:
            Path(temporary).unlink(missing_ok=True)
        raise
    for data in streams:
        write_standard_output(data)


def write_standard_output(data: bytes) -> None:
    """``data`` to file descriptor 1 (what ``-o -`` means), after anything Python has buffered
    for it. A reader that went away is a BrokenPipeError, left to the caller."""
    sys.stdout.flush()
    view = memoryview(data)
    try:
        while view:
            view = view[os.write(1, view) :]
    except BrokenPipeError:
        raise
    except OSError as error:
        raise MocapError(f"cannot write to standard output: {error.strerror or error}") from None


def _temporary(path: Path, target: Path, data: bytes) -> str:
    """``data`` in a new temporary file beside ``target`` (the file ``path`` names), with the
    permissions a plain open() gives; errors name ``path``."""
    folder = target.parent
    if not folder.is_dir():
        raise MocapError(
            f"cannot write {path}: the folder {folder} {'is not a folder' if folder.exists() else 'does not exist'}"
        )
    import tempfile  # here: commands that write nothing (`info`) start faster without it

    try:
        handle, temporary = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=folder)
    except OSError as error:
        raise MocapError(f"cannot write {path}: {error.strerror or error}") from None
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(data)
        os.chmod(temporary, 0o666 & ~_umask())  # mkstemp makes the file private
    except BaseException as error:
        Path(temporary).unlink(missing_ok=True)
        if isinstance(error, OSError):
            raise MocapError(f"cannot write {path}: {error.strerror or error}") from None
        raise
    return temporary


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


__all__ = [
    "MAX_INPUT_BYTES",
    "STANDARD_OUTPUT",
    "atomic_write",
    "atomic_write_all",
    "file_kind",
    "is_standard_output",
    "open_input",
    "output_target",
    "read_at_most",
    "read_input",
    "too_large",
    "write_standard_output",
]
