"""The clips of a source (``SRC`` of ``preprocess``): a folder, a glob, a zip or a tar, as
:class:`Item` s that say where each clip's bytes are.

Clips are taken in sorted path order from folders, globs and zips, in archive order from tars
(a compressed tar is read as a stream, once; reading it out of order would decompress it again
and again).
"""

from __future__ import annotations

import errno
import glob as globlib
import lzma
import os
import stat
import tarfile
import zipfile
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from .._utils import files as inputs
from ..bvh import parse_header, read_error, read_header
from ..bvh.header import Header
from ..errors import ArgumentError, BVHError


class BytesRead(Protocol):
    """Where :meth:`Item.header` counts the bytes it read (a clip's outcome)."""

    bytes: int


@dataclass(frozen=True)
class Item:
    """One clip to read: ``name`` (path inside SRC without .bvh), ``source`` (where it came
    from, for the manifest and error messages), ``size`` in bytes (listed: for batching and
    progress only), and where its bytes are: a file ``path``, a ``member`` of the zip at
    ``path``, ``data`` (a tar member already read), or ``refused``: why a tar member was not
    read. ``smpl_model``: for an SMPL/AMASS parameter file (``.npz``), the body model it is read
    with (it becomes a BVH clip when read, :meth:`header`). Plain values only, so a batch of
    items can be sent to the workers of a cluster."""

    name: str
    source: str
    size: int
    path: str | None = None
    member: str | None = None
    data: bytes | None = None
    refused: str | None = None
    smpl_model: str | None = None

    @property
    def is_file(self) -> bool:
        """Whether the clip is a BVH file of its own (not an archive's member, not a parameter file)."""
        return (
            self.path is not None
            and self.data is None
            and self.member is None
            and self.refused is None
            and self.smpl_model is None
        )

    def header(self, outcome: BytesRead, known=None):
        """The clip's BVH header and its text for the kernel: the file's path when the header
        came from the file's beginning (the kernel reads the rest), else the bytes. Sets
        ``outcome.bytes`` to the bytes read so far, also when the header then fails. ``known``
        (a file's): its header, its first bytes and size, or the error reading them, as read
        ahead for a batch (:func:`~expressive_mocap.dataset.heads.headers_ahead`)."""
        outcome.bytes = 0
        if self.refused is not None:
            raise BVHError(self.source, None, f"cannot read the archive member: {self.refused}")
        if isinstance(known, Header):
            return known, self.path  # counted once the kernel has read the file
        if isinstance(known, OSError):
            raise read_error(str(self.path), known)
        if self.smpl_model is not None:
            text = self.smpl_bvh(outcome)
            return parse_header(text, self.source), text
        if self.data is None and self.member is None:
            header, data = read_header(self.path, known)  # type: ignore[arg-type]
            if data is None:
                return header, self.path  # counted once the kernel has read the file
            outcome.bytes = len(data)
            return header, data
        data = self.data if self.data is not None else _member_bytes(self)
        outcome.bytes = len(data)
        return parse_header(data, self.source), data

    def smpl_bvh(self, outcome: BytesRead | None = None) -> bytes:
        """The BVH text of an SMPL/AMASS parameter file's motion on its body model
        (:func:`~expressive_mocap.skeletons.smpl.read_smpl`); a bad file is its BVHError.
        Sets ``outcome.bytes`` to the parameter file's size."""
        from ..bvh import bvh_bytes
        from ..errors import MocapError
        from ..skeletons.smpl import read_smpl

        assert self.smpl_model is not None  # only parameter files are read this way
        if self.data is not None:
            raw = self.data
        elif self.member is not None:
            raw = _member_bytes(self)
        else:
            try:
                raw = inputs.read_input(str(self.path), inputs.MAX_INPUT_BYTES)
            except OSError as error:
                raise read_error(str(self.path), error) from None
        if outcome is not None:
            outcome.bytes = len(raw)
        try:
            motion = read_smpl(raw, smpl_body(self.smpl_model), name=self.source)
            return bvh_bytes(motion)
        except MocapError as error:
            reason = str(error).removeprefix(f"{self.source}: ")
            raise BVHError(self.source, None, reason) from None


_SMPL_BODIES: dict[str, object] = {}


def smpl_body(path: str):
    """The body model at ``path`` (:func:`~expressive_mocap.skeletons.smpl.load_body_model`),
    loaded once per process (each worker of a cluster loads its own)."""
    from ..skeletons.smpl import load_body_model

    body = _SMPL_BODIES.get(path)
    if body is None:
        body = _SMPL_BODIES[path] = load_body_model(path)
    return body


# What reading one zip member can raise (a damaged, truncated or unsupported member).
_MEMBER_ERRORS = (
    zipfile.BadZipFile,
    zlib.error,
    lzma.LZMAError,
    OSError,
    EOFError,
    NotImplementedError,
    RuntimeError,
    ValueError,
)


def _member_bytes(item: Item) -> bytes:
    """A zip member's bytes, checked before decompressing: not encrypted, at most
    ``files.MAX_INPUT_BYTES`` declared, and no more than that read whatever it declares (a 1 MB zip
    can hold a 1 GiB member). Any problem is that clip's BVHError."""
    return member_beginning(item, None)[0]


def member_beginning(item: Item, length: int | None) -> tuple[bytes, int]:
    """A zip member's first ``length`` bytes (None: all of it, as :func:`_member_bytes`) and its
    declared size, checked as :func:`_member_bytes` checks it. Any problem is its BVHError."""
    assert item.path is not None and item.member is not None  # an item of a zip names both
    try:
        info = _zip(item.path).getinfo(item.member)
        if info.flag_bits & 0x1:
            raise OSError(errno.EACCES, "encrypted: members are read without a password")
        if info.file_size > inputs.MAX_INPUT_BYTES:
            raise inputs.too_large(inputs.MAX_INPUT_BYTES, item.source, info.file_size)
        with _zip(item.path).open(info) as member:
            if length is not None:
                return member.read(length), info.file_size
            return inputs.read_at_most(member, inputs.MAX_INPUT_BYTES, item.source), info.file_size
    except _MEMBER_ERRORS as error:  # a damaged member fails alone
        reason = error.strerror if isinstance(error, OSError) and error.strerror else error
        raise BVHError(item.source, None, f"cannot read the archive member: {reason}") from None


_ZIPS: dict[str, zipfile.ZipFile] = {}


def _zip(path: str) -> zipfile.ZipFile:
    """One open ZipFile per archive and process (each worker of a cluster opens its own)."""
    archive = _ZIPS.get(path)
    if archive is None:
        archive = _ZIPS[path] = zipfile.ZipFile(path)
    return archive


def _is_tar(path: Path) -> bool:
    return any(path.name.lower().endswith(s) for s in (".tar", ".tar.gz", ".tgz", ".tar.xz", ".txz", ".tar.bz2"))


def _clip_name(relative: str) -> str:
    return relative[:-4] if relative.lower().endswith((".bvh", ".npz")) else relative


def _is_clip(name: str, smpl_model: str | None) -> bool:
    """Whether a file of this name is a clip: a BVH file, or with a body model an SMPL/AMASS
    parameter file (not AMASS's ``shape.npz``, a subject's body shape with no motion)."""
    lower = name.lower()
    if lower.endswith(".bvh"):
        return True
    return (
        smpl_model is not None and lower.endswith(".npz") and lower.replace("\\", "/").rsplit("/", 1)[-1] != "shape.npz"
    )


def _parameters(name: str, smpl_model: str | None) -> str | None:
    """The body model a clip of this name is read with: ``smpl_model`` for an ``.npz``."""
    return smpl_model if name.lower().endswith(".npz") else None


def _listed_size(path: str) -> int:
    """The size of a regular file within the bound (a stat, no open: listing stays fast), 0 for
    anything else: a FIFO, device, dangling link or larger file is not read, its clip fails
    with the reason when read."""
    try:
        info = os.stat(path)
    except OSError:
        return 0
    return info.st_size if stat.S_ISREG(info.st_mode) and info.st_size <= inputs.MAX_INPUT_BYTES else 0


def _folder(root: Path, smpl_model: str | None = None) -> list[Item]:
    """The ``*.bvh`` files below ``root`` (any case; symlinked folders are not followed), by name,
    and with ``smpl_model`` the ``*.npz`` parameter files. os.walk + plain strings: an archive of
    thousands of files is listed in milliseconds."""
    prefix, items = os.path.join(str(root), ""), []
    for folder, _, names in os.walk(root):
        for name in names:
            if _is_clip(name, smpl_model):
                path = os.path.join(folder, name)
                relative = _clip_name(path[len(prefix) :].replace(os.sep, "/"))
                items.append(
                    Item(relative, path, _listed_size(path), path=path, smpl_model=_parameters(name, smpl_model))
                )
    return sorted(items, key=lambda i: i.name)


def _files(paths, root: Path, smpl_model: str | None = None) -> list[Item]:
    items = [
        Item(
            _clip_name(p.relative_to(root).as_posix()),
            str(p),
            _listed_size(str(p)),
            path=str(p),
            smpl_model=_parameters(p.name, smpl_model),
        )
        for p in paths
    ]
    return sorted(items, key=lambda i: i.name)


@dataclass
class Source:
    """The clips of SRC: a folder (recursive ``*.bvh``), a glob, a .zip or a tar (read in place)."""

    description: str
    items: list[Item] | None  # known up front (folders, globs, zips); None for a tar stream
    _stream: Callable[[], Iterator[Item]] | None = None
    _close: Callable[[], None] | None = None

    def __iter__(self) -> Iterator[Item]:
        if self.items is not None:
            return iter(self.items)
        assert self._stream is not None  # a source lists its items or streams them
        return self._stream()

    def close(self) -> None:
        if self._close is not None:
            self._close()


def open_source(src: str | os.PathLike, smpl_model: str | os.PathLike | None = None) -> Source:
    """The clips of ``src``: a folder (``*.bvh`` found recursively), a glob pattern
    (``"data/*_walk_*.bvh"``), a ``.zip`` or a ``.tar``/``.tar.gz``/``.tar.xz`` archive. With
    ``smpl_model`` (an SMPL-family body model file, checked here), SMPL/AMASS parameter files
    (``*.npz``) are clips too, each read with it."""
    text = str(src)
    path = Path(src)
    model = None
    if smpl_model is not None:
        model = os.path.abspath(smpl_model)
        smpl_body(model)  # a bad body model fails before any clip, naming the file
    if path.is_dir():
        return Source(f"folder {path}", _folder(path, model))
    if path.is_file() and zipfile.is_zipfile(path):
        try:
            archive = _zip(str(path))
        except (zipfile.BadZipFile, OSError, ValueError) as error:  # found a zip's end, but not a readable directory
            raise ArgumentError(f"{path}: cannot read the zip archive ({type(error).__name__}: {error})") from None
        members = [m for m in archive.infolist() if not m.is_dir() and _is_clip(m.filename, model)]
        # A member over the bound is refused unread: it counts 0 towards the progress bar's total.
        items = [
            Item(
                _clip_name(m.filename),
                f"{path}:{m.filename}",
                m.file_size if m.file_size <= inputs.MAX_INPUT_BYTES else 0,
                path=str(path),
                member=m.filename,
                smpl_model=_parameters(m.filename, model),
            )
            for m in members
        ]
        return Source(f"zip {path}", sorted(items, key=lambda i: i.name), _close=lambda: _ZIPS.pop(str(path)).close())
    if path.is_file() and _is_tar(path):
        return Source(f"tar {path}", None, _stream=lambda: _tar_stream(path, model))
    if any(c in text for c in "*?["):
        # Anything but a folder: a FIFO or a device matched is that clip's failure, not skipped.
        matches = [Path(p) for p in globlib.glob(text, recursive=True) if _is_clip(p, model) and not os.path.isdir(p)]
        if not matches:
            raise ArgumentError(f"no {'.bvh or .npz' if model else '.bvh'} files match {text}")
        # Clip names are paths below the pattern's last folder without wildcards.
        prefix = text[: min(text.index(c) for c in "*?[" if c in text)]
        root = Path(prefix) if prefix.endswith(os.sep) else Path(prefix).parent
        return Source(f"glob {text}", _files(matches, root, model))
    if path.is_file():
        raise ArgumentError(f"{path}: not a folder, .zip or .tar(.gz/.xz) archive of BVH files")
    if path.exists():  # a FIFO, a device: never opened
        raise ArgumentError(
            f"{path}: {inputs.file_kind(path.stat().st_mode)}, not a folder, .zip or .tar(.gz/.xz) archive of BVH files"
        )
    raise ArgumentError(f"{path}: no such folder or archive")


def _tar_stream(path: Path, smpl_model: str | None) -> Iterator[Item]:
    """The .bvh members of a tar (and .npz ones with ``smpl_model``) in archive order, each read
    as the stream passes it: only regular files of at most ``files.MAX_INPUT_BYTES`` (checked
    before reading), others are their clip's failure."""
    limit = inputs.MAX_INPUT_BYTES
    try:
        with tarfile.open(path, mode="r|*") as archive:
            for member in archive:
                if member.isdir() or not _is_clip(member.name, smpl_model):
                    continue
                name, source = _clip_name(member.name), f"{path}:{member.name}"
                parameters = _parameters(member.name, smpl_model)
                if not member.isfile():
                    why = f"{_tar_kind(member)}, not a regular file: only regular files are read"
                    yield Item(name, source, 0, refused=why, smpl_model=parameters)
                elif member.size > limit:
                    why = str(inputs.too_large(limit, source, member.size).strerror)
                    yield Item(name, source, 0, refused=why, smpl_model=parameters)
                else:
                    data = inputs.read_at_most(archive.extractfile(member), limit, source)
                    yield Item(name, source, len(data), data=data, smpl_model=parameters)
    except (tarfile.TarError, EOFError, OSError) as error:
        raise ArgumentError(f"{path}: cannot read the tar archive ({type(error).__name__}: {error})") from None


def _tar_kind(member: tarfile.TarInfo) -> str:
    """What a tar member that is not a regular file is, in words (as files.file_kind)."""
    for test, kind in (
        (member.issym, "a symbolic link"),
        (member.islnk, "a hard link"),
        (member.isfifo, "a FIFO"),
        (member.ischr, "a character device"),
        (member.isblk, "a block device"),
    ):
        if test():
            return kind
    return "a special file"


__all__ = ["BytesRead", "Item", "Source", "member_beginning", "open_source", "smpl_body"]
