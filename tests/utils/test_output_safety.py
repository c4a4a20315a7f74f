"""No output destroys or silently corrupts a file that is not ours to replace: a device, FIFO,
socket or folder at the destination (or behind a symlink) is refused before any work and left as
it was; ``-`` and ``/dev/stdout`` stream to standard output; a symlink to a regular file is
written through; every write error names the path; nothing non-finite is written; resampling
is bounded before it allocates. Device nodes are made in tmp_path (a copy of /dev/null), so a
regression could never replace the machine's own /dev/null."""

from __future__ import annotations

import errno
import io
import os
import socket
import stat
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap._utils import files as em_io
from expressive_mocap.cli import main
from expressive_mocap.errors import MocapError
from expressive_mocap.procedural import walk_and_wave

needs_root = pytest.mark.skipif(os.geteuid() != 0, reason="making a device node (mknod) needs root")


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    path = tmp_path_factory.mktemp("walk") / "walk.bvh"
    em.write_bvh(walk_and_wave(seconds=1.0).walk, path)
    return path


def make(kind: str, path: Path) -> tuple[int, int]:
    """A non-regular file of ``kind`` at ``path``; its (file type, device) to check it survives."""
    if kind == "character device":
        os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # what /dev/null is
    elif kind == "FIFO":
        os.mkfifo(path)
    elif kind == "socket":
        os.chdir(path.parent)  # AF_UNIX paths are short: bind the relative name
        server = socket.socket(socket.AF_UNIX)
        server.bind(path.name)
        server.close()  # the socket file stays
    elif kind == "folder":
        path.mkdir()
    elif kind == "symlink to a character device":
        make("character device", path.with_name("device"))
        path.symlink_to("device")
    info = os.stat(path)
    return stat.S_IFMT(info.st_mode), info.st_rdev


KINDS = [
    pytest.param("character device", marks=needs_root),
    "FIFO",
    "socket",
    "folder",
    pytest.param("symlink to a character device", marks=needs_root),
]


@pytest.mark.parametrize("kind", KINDS)
def test_write_bvh_refuses_a_destination_that_is_not_a_regular_file_and_leaves_it_be(kind, walk, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    destination = tmp_path / "out.bvh"
    before = make(kind, destination)
    with pytest.raises(MocapError) as error:
        em.write_bvh(em.read_bvh(walk), destination)
    message = str(error.value)
    assert (
        message.startswith(f"cannot write {destination}: it is a")
        and kind.split()[-1] in message
        and "\n" not in message
    )
    info = os.stat(destination)
    assert (stat.S_IFMT(info.st_mode), info.st_rdev) == before, "the destination was replaced"
    assert [p.name for p in tmp_path.iterdir() if p.name.endswith(".tmp")] == []


@needs_root
@pytest.mark.parametrize(
    "argv",
    [
        ["convert", "{walk}", "-o", "{out}"],
        ["positions", "{walk}", "-o", "{out}"],
        ["convert", "{walk}", "--fps", "60", "-o", "{out}"],
    ],
)
def test_the_cli_never_replaces_a_device_node(argv, walk, tmp_path, capsys):
    device = tmp_path / "null"
    before = make("character device", device)
    status = main([a.format(walk=walk, out=device) for a in argv])
    err = capsys.readouterr().err
    assert (
        status == 1
        and err
        == f"expressive-mocap: error: cannot write {device}: it is a character device, not a regular file "
        "(outputs replace regular files only; '-' writes to standard output)\n"
    )
    info = os.stat(device)
    assert (stat.S_IFMT(info.st_mode), info.st_rdev) == before


@pytest.mark.parametrize("command", ["convert", "positions"])
def test_the_real_dev_null_stays_a_character_device(command, walk, capsys):
    # Run only once the copies above pass: the check refuses before anything is written.
    assert main([command, str(walk), "-o", "/dev/null"]) == 1
    assert "it is a character device" in capsys.readouterr().err
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode) and os.stat("/dev/null").st_rdev == os.makedev(1, 3)


def test_a_fifo_destination_does_not_block(walk, tmp_path):
    # Opening a FIFO to write would wait for a reader for ever; it is refused from its lstat.
    fifo = tmp_path / "pipe.bvh"
    os.mkfifo(fifo)
    with pytest.raises(MocapError, match="it is a FIFO"):
        em_io.atomic_write(fifo, b"data")
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


@pytest.mark.parametrize("name", ["-", "/dev/stdout"])
def test_dash_and_dev_stdout_stream_the_bvh_and_reports_go_to_stderr(name, walk, tmp_path, capfdbinary, monkeypatch):
    monkeypatch.chdir(tmp_path)  # were "-" taken for a file name, it would land here
    assert main(["convert", str(walk), "--fps", "60", "-o", str(tmp_path / "file.bvh")]) == 0
    capfdbinary.readouterr()
    link = os.lstat("/dev/stdout")
    assert main(["convert", str(walk), "--fps", "60", "-o", name]) == 0
    out, err = capfdbinary.readouterr()
    assert out == (tmp_path / "file.bvh").read_bytes()  # the data alone, byte for byte
    assert err.startswith(f"wrote {name}: ".encode())
    assert os.lstat("/dev/stdout").st_ino == link.st_ino, "/dev/stdout was replaced"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["file.bvh"]


def test_positions_stream_an_npz(walk, tmp_path, capfdbinary, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["positions", str(walk), "-o", "-"]) == 0
    out, _ = capfdbinary.readouterr()
    with np.load(io.BytesIO(out)) as arrays:
        assert arrays["positions"].shape == (em.read_bvh(walk).n_frames, 22, 3)


def test_calibrate_streams_the_model_and_reports_on_stderr(walk, tmp_path, capfdbinary, monkeypatch):
    from expressive_mocap.decoupling.body_model import BodyModel

    monkeypatch.chdir(tmp_path)
    assert main(["calibrate", str(walk), "-o", "-"]) == 0
    out, err = capfdbinary.readouterr()
    assert BodyModel.load(out).calibration_angles() and b"largest corrections" in err and list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "argv",
    [
        ["render", "{walk}", "-o", "-"],
        ["decouple", "{walk}", "-o", "-"],
        ["footsteps", "{walk}", "--plot", "-"],
        ["demo", "-o", "-"],
        ["render", "{walk}", "-o", "/dev/stdout"],
    ],
)
def test_commands_that_cannot_stream_refuse_standard_output(argv, walk, tmp_path, capfd, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status = main([a.format(walk=walk) for a in argv])
    out, err = capfd.readouterr()
    assert status == 1 and out == "" and err.count("\n") == 1 and "does not write to standard output" in err, err
    assert list(tmp_path.iterdir()) == []  # no file called "-" or "-_body.bvh" either


def test_a_symlink_to_a_regular_file_is_written_through(walk, tmp_path):
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    target = elsewhere / "take.bvh"
    target.write_text("old")
    link = tmp_path / "latest.bvh"
    link.symlink_to(target)
    assert main(["convert", str(walk), "--scale", "2", "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target), "the link was replaced"
    assert em.read_bvh(target).skeleton.offsets == pytest.approx(2 * em.read_bvh(walk).skeleton.offsets)
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["elsewhere", "latest.bvh", "take.bvh"]  # no temporary left


@pytest.mark.parametrize("link_to", ["missing.bvh", "itself"])
def test_a_broken_symlink_is_refused(link_to, walk, tmp_path):
    link = tmp_path / "out.bvh"
    link.symlink_to(link if link_to == "itself" else tmp_path / link_to)
    with pytest.raises(MocapError, match="does not exist" if link_to == "missing.bvh" else "leads back to itself"):
        em.write_bvh(em.read_bvh(walk), link)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.bvh"] and link.is_symlink()


class _FullDisk:
    """A file whose write stops halfway with ENOSPC, as a full disk does."""

    def __init__(self, handle):
        self.handle = handle

    def write(self, data):
        self.handle.write(data[: len(data) // 2])
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.handle.close()


def test_a_full_disk_names_the_file_removes_the_temporary_and_keeps_the_old_file(walk, tmp_path, monkeypatch):
    destination = tmp_path / "out.bvh"
    destination.write_bytes(b"the user's file")
    motion, real_fdopen = em.read_bvh(walk), os.fdopen
    monkeypatch.setattr(em_io.os, "fdopen", lambda fd, mode: _FullDisk(real_fdopen(fd, mode)))
    with pytest.raises(MocapError) as error:
        em.write_bvh(motion, destination)
    assert str(error.value) == f"cannot write {destination}: No space left on device"
    assert [p.name for p in tmp_path.iterdir()] == ["out.bvh"] and destination.read_bytes() == b"the user's file"


def test_a_failed_rename_names_the_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    def failing_replace(source, target):
        raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))

    monkeypatch.setattr(em_io.os, "replace", failing_replace)
    with pytest.raises(MocapError, match=f"^cannot write {tmp_path / 'a.csv'}: Invalid cross-device link$"):
        em_io.atomic_write_all({tmp_path / "a.csv": b"1", tmp_path / "b.csv": b"2"})
    assert list(tmp_path.iterdir()) == []


def test_a_full_standard_output_is_named(monkeypatch):
    monkeypatch.setattr(
        em_io.os, "write", lambda fd, data: (_ for _ in ()).throw(OSError(errno.ENOSPC, os.strerror(errno.ENOSPC)))
    )
    with pytest.raises(MocapError, match="^cannot write to standard output: No space left on device$"):
        em_io.atomic_write("-", b"data")


# --- resampling is bounded before it allocates ----------------------------------------------

TWO_JOINTS = (
    b"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\nJOINT b\n{\nOFFSET 0 %s 0\n"
    b"CHANNELS 3 Zrotation Xrotation Yrotation\nEnd Site\n{\nOFFSET 0 1 0\n}\n}\n}\n"
    b"MOTION\nFrames: 2\nFrame Time: %s\n%s\n%s\n"
)


def tiny(
    tmp_path, frame_time=b"0.1", offset=b"1", first=b"0 0 0 0 0 0", second=b"1 1 1 10 10 10", name="tiny.bvh"
) -> Path:
    path = tmp_path / name
    path.write_bytes(TWO_JOINTS % (offset, frame_time, first, second))
    return path


@pytest.mark.parametrize("frame_time", [b"1000000", b"1e300", b"1e308"])
def test_convert_fps_on_a_huge_frame_time_is_a_one_line_error(frame_time, tmp_path, capsys):
    path = tiny(tmp_path, frame_time=frame_time)  # a 230-byte file; at 120 fps 10^6 s would be 7 GiB of frames
    status = main(["convert", str(path), "--fps", "120", "-o", str(tmp_path / "out.bvh")])
    err = capsys.readouterr().err
    assert (
        status == 1
        and err.count("\n") == 1
        and err.startswith(f"expressive-mocap: error: {path}: --fps 120: ")
        and "joint-frames" in err
    ), err
    assert not (tmp_path / "out.bvh").exists()


@pytest.mark.parametrize("frame_time", [b"1000000", b"1e300"])
def test_resample_refuses_before_allocating(frame_time, tmp_path):
    import tracemalloc

    motion = em.read_bvh(tiny(tmp_path, frame_time=frame_time))
    tracemalloc.start()  # NumPy reports its allocations to tracemalloc
    try:
        with pytest.raises(MocapError, match="joint-frames"):
            motion.resample(fps=120)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1 << 20, f"{peak:,} bytes allocated before refusing"


@pytest.mark.parametrize("fps", [0, -30, float("nan"), float("inf"), 1e-320, True, "30"])
def test_resample_refuses_a_bad_fps(fps, walk):
    with pytest.raises(MocapError, match="^resample: .*fps"):
        em.read_bvh(walk).resample(fps=fps)


@pytest.mark.parametrize("n_frames", [1, 0, -5, 2.5, float("nan"), float("inf"), True, 10**12])
def test_resample_refuses_a_bad_frame_count(n_frames, walk):
    with pytest.raises(MocapError, match="^resample: n_frames"):
        em.read_bvh(walk).resample(n_frames=n_frames)


def test_resample_at_the_bound_and_beyond(walk, monkeypatch):
    from expressive_mocap import motion as em_motion

    monkeypatch.setattr(em_motion, "MAX_RESAMPLED_JOINT_FRAMES", 22 * 100)
    motion = em.read_bvh(walk)  # 22 joints
    assert motion.resample(n_frames=100).n_frames == 100
    with pytest.raises(MocapError, match="101 frames x 22 joints, more than the 2,200 joint-frames"):
        motion.resample(n_frames=101)


def test_resampling_in_blocks_gives_the_same_frames(walk, monkeypatch):
    from expressive_mocap import motion as em_motion

    motion = em.read_bvh(walk)
    whole = motion.resample(fps=97.0)
    monkeypatch.setattr(em_motion, "_RESAMPLE_BLOCK", 22 * 7)  # blocks of 7 frames
    blocks = motion.resample(fps=97.0)
    assert (
        whole.n_frames > 7 * 3
        and np.array_equal(whole.rotations, blocks.rotations)
        and np.array_equal(whole.translations, blocks.translations)
    )


# --- nothing non-finite is written; numeric options say what they expect ---------------------


def test_convert_scale_past_float64_is_refused_naming_the_file_and_option(tmp_path, capsys):
    path = tiny(tmp_path, offset=b"1e308")
    status = main(["convert", str(path), "--scale", "10", "-o", str(tmp_path / "out.bvh")])
    err = capsys.readouterr().err
    assert (
        status == 1
        and err.count("\n") == 1
        and err.startswith(f"expressive-mocap: error: {path}: --scale 10: ")
        and "finite" in err
    ), err
    assert not (tmp_path / "out.bvh").exists()


@pytest.mark.parametrize("where", ["translation", "End Site"])
def test_scaled_refuses_lengths_that_overflow(where, tmp_path):
    if where == "translation":
        path = tiny(tmp_path, first=b"0 1e308 0 0 0 0")
    else:
        path = tmp_path / "site.bvh"
        path.write_bytes(
            b"HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n"
            b"End Site\n{\nOFFSET 0 1e308 0\n}\n}\n"
            b"MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0\n"
        )
    motion = em.read_bvh(path)
    with pytest.raises(MocapError, match=r"^scaled: x 10 takes an? \w+ beyond float64 \(the largest is 1e\+308\)"):
        motion.scaled(10)
    assert np.isfinite(motion.scaled(0.5).translations).all()


@pytest.mark.parametrize("bad", [np.inf, np.nan])
def test_write_bvh_refuses_non_finite_values_naming_the_path_frame_and_channel(bad, walk, tmp_path):
    motion = em.read_bvh(walk)
    translations = motion.translations.copy()
    translations[3, 0, 1] = bad
    destination = tmp_path / "out.bvh"
    destination.write_bytes(b"the user's file")
    with pytest.raises(
        MocapError,
        match=(
            rf"^cannot write {destination}: frame 3, joint_Root Yposition is {bad}: "
            r"a BVH file holds finite numbers only$"
        ),
    ):
        em.write_bvh(em.Motion(motion.skeleton, motion.rotations, translations, motion.frame_time), destination)
    assert destination.read_bytes() == b"the user's file"


def test_an_infinite_end_site_is_refused_when_the_skeleton_is_made(walk):
    skeleton = em.read_bvh(walk).skeleton
    with pytest.raises(MocapError, match="End Site offsets must be finite"):
        em.Skeleton(
            skeleton.names,
            skeleton.parents,
            skeleton.offsets,
            skeleton.channels,
            [(skeleton.end_sites[0][0], (0.0, np.inf, 0.0))],
        )


def test_positions_past_float64_are_refused_not_written(tmp_path, capsys):
    path = tiny(tmp_path, offset=b"1e308", first=b"0 1e308 0 0 0 0")
    status = main(["positions", str(path), "-o", str(tmp_path / "p.npz")])
    err = capsys.readouterr().err
    assert status == 1 and err.count("\n") == 1 and f"{path}: the position of b at frame 0 is not finite" in err, err
    assert not (tmp_path / "p.npz").exists()


@pytest.mark.parametrize(
    "argv",
    [
        ["convert", "{walk}", "-o", "{out}", "--fps", "nan"],
        ["convert", "{walk}", "-o", "{out}", "--fps", "inf"],
        ["convert", "{walk}", "-o", "{out}", "--scale", "0"],
        ["convert", "{walk}", "-o", "{out}", "--scale", "nan"],
        ["convert", "{walk}", "-o", "{out}", "--scale", "inf"],
        ["convert", "{walk}", "-o", "{out}", "--scale", "-2"],
        ["modulate", "{walk}", "--scale", "nan", "-o", "{out}"],
        ["modulate", "{walk}", "--scale", "inf", "-o", "{out}"],
        ["exaggerate", "--model", "m.npz", "--input", "{walk}", "--to", "nan", "-o", "{out}"],
        ["exaggerate", "--model", "m.npz", "--input", "{walk}", "--to", "2", "--fade", "inf", "-o", "{out}"],
        ["footsteps", "{walk}", "--floor", "nan"],
        ["render", "{walk}", "--poses", "0", "-o", "{out}"],
    ],
)
def test_numeric_options_are_finite_or_a_one_line_usage_error(argv, walk, tmp_path, capsys):
    out = tmp_path / "out.bvh"
    with pytest.raises(SystemExit) as exit_:
        main([a.format(walk=walk, out=out) for a in argv])
    err = capsys.readouterr().err
    assert exit_.value.code == 2 and err.count("\n") == 1 and "must be " in err and "finite, got " in err, err
    assert list(tmp_path.iterdir()) == []


def test_a_level_intensity_must_be_finite(walk, capsys):
    assert main(["rank", "--level", "nan", str(walk), "--level", "2", str(walk)]) == 1
    assert "--level nan: the first value is the intensity, a finite number" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "what"),
    [
        (["convert", "{walk}", "-o", "{walk}"], "the input"),
        (["modulate", "{wave}", "--scale", "2", "-o", "{wave}"], "the input"),
        (["retarget", "{walk}", "--to", "{wave}", "-o", "{wave}"], "--to"),
        (["mix", "--body", "{walk}", "--expressive", "{wave}", "-o", "{walk}"], "--body"),
        (["mix", "--body", "{walk}", "--expressive", "{wave}", "-o", "{link}"], "--expressive"),
        (["blend", "{walk}", "{wave}", "--body-window", "5:10", "-o", "{hard}"], "the input"),
    ],
)
def test_an_output_that_is_or_resolves_to_an_input_is_refused(argv, what, walk, tmp_path, capsys):
    """Writing over an input, by its name, a symlink or a hard link to it, is refused before any
    work with one line naming the input; every input is left as it was."""
    wave, kept = tmp_path / "wave.bvh", tmp_path / "walk.bvh"
    em.write_bvh(walk_and_wave(seconds=1.0).waving, wave)
    kept.write_bytes(walk.read_bytes())
    (tmp_path / "link.bvh").symlink_to(wave)
    os.link(wave, tmp_path / "hard.bvh")
    before = {p: p.read_bytes() for p in (wave, kept)}
    names = {"walk": kept, "wave": wave, "link": tmp_path / "link.bvh", "hard": tmp_path / "hard.bvh"}
    assert main([a.format(**names) for a in argv]) == 1
    err = capsys.readouterr().err.strip()
    assert (
        len(err.splitlines()) == 1
        and "cannot write" in err
        and f"it is {what}" in err
        and "choose another output" in err
    )
    assert {p: p.read_bytes() for p in before} == before
