"""Every command that writes: files appear only where asked (never next to an input), a missing,
non-folder or unwritable output folder is a one-line error before any work, inputs are never
touched, and a write interrupted midway leaves no partial file."""

import argparse
import hashlib
import os
from pathlib import Path

import pytest

import expressive_mocap as em
from expressive_mocap._utils import files as em_io
from expressive_mocap.cli import build_parser, main
from expressive_mocap.procedural import loaded_walk, procedural_walk, walk_and_wave


@pytest.fixture(scope="module")
def inputs(tmp_path_factory):
    """Input files in a folder of their own (watched for stray outputs)."""
    folder = tmp_path_factory.mktemp("inputs")
    pair = walk_and_wave(seconds=2.0)
    paths = {"walk": folder / "walk.bvh", "wave": folder / "wave.bvh", "fast": folder / "fast.bvh"}
    em.write_bvh(pair.walk, paths["walk"])
    em.write_bvh(pair.waving, paths["wave"])
    em.write_bvh(procedural_walk(seconds=2.0, speed=1.5), paths["fast"])
    paths["positions"] = folder / "walk.npz"
    assert main(["positions", str(paths["walk"]), "-o", str(paths["positions"])]) == 0
    for k in (1, 2):
        for p in (0, 1):
            paths[f"level{k}_{p}"] = folder / f"level{k}_{p}.bvh"
            em.write_bvh(loaded_walk(k, seconds=3.0, wobble=0.3, seed=10 * p + k), paths[f"level{k}_{p}"])
    models = tmp_path_factory.mktemp("models")
    paths["exaggeration"] = models / "exaggeration.npz"
    assert main(["rank", *levels(paths), "-o", str(paths["exaggeration"])]) == 0
    return {name: str(path) for name, path in paths.items()} | {"folder": folder}


def levels(i):
    return [a for k in (1, 2) for a in ("--level", str(k), str(i[f"level{k}_0"]), str(i[f"level{k}_1"]))]


def command(name, i, out):
    """argv of command ``name`` writing into folder ``out``, and the outputs it must write."""
    return {
        "convert": (["convert", i["walk"], "-o", out / "c.bvh"], ["c.bvh"]),
        "retarget": (["retarget", i["walk"], "--to", i["wave"], "-o", out / "rt.bvh"], ["rt.bvh"]),
        "positions": (["positions", i["walk"], "-o", out / "p.npz"], ["p.npz"]),
        "fit": (["fit", i["positions"], "--to", i["wave"], "-o", out / "fit.bvh"], ["fit.bvh"]),
        "render": (["render", i["walk"], "--poses", "2", "-o", out / "r.png"], ["r.png"]),
        "decouple": (["decouple", i["wave"], "-o", out / "d"], ["d_body.bvh", "d_expressive.bvh", "d_activity.csv"]),
        "modulate": (["modulate", i["wave"], "--scale", "1.5", "-o", out / "m.bvh"], ["m.bvh"]),
        "mix": (["mix", "--body", i["walk"], "--expressive", i["wave"], "-o", out / "x.bvh"], ["x.bvh"]),
        "blend": (["blend", i["walk"], i["wave"], "--body-window", "10:20", "-o", out / "b.bvh"], ["b.bvh"]),
        "calibrate": (["calibrate", i["walk"], "-o", out / "cal.npz"], ["cal.npz"]),
        "train": (
            [
                "train",
                i["walk"],
                i["fast"],
                "--hidden",
                "3",
                "--regression-hidden",
                "3",
                "--max-iter",
                "2",
                "-o",
                out / "t.npz",
            ],
            ["t.npz"],
        ),
        "rank": (["rank", *levels(i), "-o", out / "rank.npz", "-o", out / "rank.png"], ["rank.npz", "rank.png"]),
        "exaggerate": (
            ["exaggerate", "--model", i["exaggeration"], "--input", i["level1_0"], "--to", "2", "-o", out / "e.bvh"],
            ["e.bvh"],
        ),
        "footsteps": (["footsteps", i["walk"], "--plot", out / "f.png"], ["f.png"]),
        "demo": (["demo", "--seconds", "1", "-o", out / "demo"], ["demo"]),
        "preprocess": (["preprocess", i["folder"], "-q", "-o", out / "ds"], ["ds"]),
    }[name]


WRITERS = [
    "convert",
    "retarget",
    "positions",
    "fit",
    "render",
    "decouple",
    "modulate",
    "mix",
    "blend",
    "calibrate",
    "train",
    "rank",
    "exaggerate",
    "footsteps",
    "demo",
    "preprocess",
]


def test_the_list_covers_every_command_that_writes():
    subcommands = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)).choices
    writing = {name for name, p in subcommands.items() if any(a.dest in ("output", "plot") for a in p._actions)}
    assert writing == set(WRITERS)


def snapshot(folder):
    return {p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in sorted(folder.rglob("*")) if p.is_file()}


def run(name, inputs, out, capsys):
    argv, expected = command(name, inputs, out)
    before = snapshot(inputs["folder"])
    status = main([str(a) for a in argv])
    captured = capsys.readouterr()
    assert snapshot(inputs["folder"]) == before, "an input was changed or a file was written next to the inputs"
    return status, captured.err, expected


@pytest.mark.parametrize("name", WRITERS)
def test_outputs_go_only_where_asked(name, inputs, tmp_path, capsys):
    status, err, expected = run(name, inputs, tmp_path, capsys)
    assert status == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(expected)
    assert not [p for p in tmp_path.rglob("*.tmp")], "a temporary file was left behind"
    if name == "demo":  # the list its outputs are checked from before any work
        from expressive_mocap.cli.demo import DEMO_FILES

        assert sorted(p.name for p in (tmp_path / "demo").iterdir()) == sorted(DEMO_FILES)


@pytest.mark.parametrize("problem", ["missing", "a file"])
@pytest.mark.parametrize("name", WRITERS)
def test_a_bad_output_folder_is_a_one_line_error_before_any_work(name, problem, inputs, tmp_path, capsys):
    folder = tmp_path / "nowhere"
    if problem == "a file":
        folder.write_text("not a folder")
    status, err, _ = run(name, inputs, folder, capsys)
    assert status == 1 and err.count("\n") == 1, err
    assert ("does not exist" if problem == "missing" else "is not a folder") in err, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ([] if problem == "missing" else ["nowhere"])


class _FailingFile:
    """A file whose write stops halfway with "no space left on device"."""

    def __init__(self, handle):
        self.handle = handle

    def write(self, data):
        self.handle.write(data[: len(data) // 2])
        raise OSError(28, "No space left on device")

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.handle.close()


@pytest.mark.parametrize("name", WRITERS)
def test_an_interrupted_write_leaves_no_partial_file(name, inputs, tmp_path, capsys, monkeypatch):
    real_fdopen = em_io.os.fdopen
    # Inputs are opened with os.fdopen too (files.open_input): only files opened to write fail.
    monkeypatch.setattr(
        em_io.os,
        "fdopen",
        lambda fd, mode: _FailingFile(real_fdopen(fd, mode)) if "w" in mode else real_fdopen(fd, mode),
    )
    status, err, _ = run(name, inputs, tmp_path, capsys)
    # Progress lines (train) may come first; the error is the last line, and one line.
    assert (
        status == 1
        and err.splitlines()[-1].startswith("expressive-mocap: error:")
        and "No space left" in err.splitlines()[-1]
    ), err
    # ... and names the file it was writing (preprocess's own journal writes are not in io.py).
    assert name == "preprocess" or f"cannot write {tmp_path}{os.sep}" in err.splitlines()[-1], err
    files = [p for p in tmp_path.rglob("*") if p.is_file()]
    # Only preprocess keeps finished batches, to resume from them (not a dataset without its manifest).
    assert files == [] or (name == "preprocess" and not any(p.name == "manifest.json" for p in files)), files


def test_decouple_writes_its_three_files_together_or_not_at_all(inputs, tmp_path, capsys, monkeypatch):
    real_fdopen, opened = em_io.os.fdopen, []

    def third_write_fails(fd, mode):
        handle = real_fdopen(fd, mode)
        if "w" not in mode:
            return handle  # an input (files.open_input)
        opened.append(fd)
        return _FailingFile(handle) if len(opened) == 3 else handle

    monkeypatch.setattr(em_io.os, "fdopen", third_write_fails)
    status, err, _ = run("decouple", inputs, tmp_path, capsys)
    assert status == 1 and "No space left" in err, err
    assert len(opened) == 3 and list(tmp_path.iterdir()) == [], (
        "the two files written before the failure must not appear"
    )


@pytest.mark.parametrize("name", WRITERS)
def test_an_unwritable_output_folder_is_a_one_line_error(name, inputs, tmp_path, capsys, monkeypatch):
    # The tests run as root, which chmod cannot stop: the permission check is made to say no.
    import expressive_mocap.cli as cli

    real_access = os.access
    monkeypatch.setattr(
        cli.os, "access", lambda path, mode: False if Path(path) == tmp_path else real_access(path, mode)
    )
    status, err, _ = run(name, inputs, tmp_path, capsys)
    assert status == 1 and err.count("\n") == 1 and "is not writable" in err, err
    assert list(tmp_path.iterdir()) == []


def _no_work(*args, **kwargs):
    raise AssertionError("the command started working before refusing its output")


@pytest.mark.parametrize(
    ("name", "kind"),
    [
        (name, kind)
        for name in WRITERS
        for kind in ("FIFO", "folder", "character device")
        if not (kind == "folder" and name in ("demo", "preprocess"))
    ],
)  # their OUT is a folder
def test_an_output_that_is_not_a_regular_file_is_refused_before_any_work(
    name, kind, inputs, tmp_path, capsys, monkeypatch
):
    import stat

    import expressive_mocap.dataset as preprocess
    import expressive_mocap.procedural as demo
    from expressive_mocap.cli import common, data, decoupling, exaggeration, files
    from expressive_mocap.cli import demo as cli_demo

    if kind == "character device" and os.geteuid() != 0:
        pytest.skip("mknod needs root")
    special = tmp_path / command(name, inputs, tmp_path)[1][0]  # decouple: PREFIX_body.bvh
    {
        "FIFO": os.mkfifo,
        "folder": os.mkdir,
        "character device": lambda p: os.mknod(p, stat.S_IFCHR | 0o666, os.makedev(1, 3)),
    }[kind](special)
    before = os.lstat(special)
    commands = [
        (module, "read_bvh")
        for module in (common, data, decoupling, exaggeration, files, cli_demo)
        if hasattr(module, "read_bvh")
    ]
    for module, function in (*commands, (demo, "walk_and_wave"), (preprocess, "preprocess")):
        monkeypatch.setattr(module, function, _no_work)
    status, err, _ = run(name, inputs, tmp_path, capsys)
    assert status == 1 and err.count("\n") == 1 and f"cannot write {special}: it is a {kind}, not a " in err, err
    after = os.lstat(special)
    assert (stat.S_IFMT(after.st_mode), after.st_ino, after.st_rdev) == (
        stat.S_IFMT(before.st_mode),
        before.st_ino,
        before.st_rdev,
    )
    assert [p.name for p in tmp_path.iterdir()] == [special.name]


def test_demo_checks_every_file_it_will_write_in_an_existing_folder(tmp_path, capsys, monkeypatch):
    import expressive_mocap.procedural as demo

    (tmp_path / "demo").mkdir()
    os.mkfifo(tmp_path / "demo" / "decouple.gif")  # the last file demo writes
    monkeypatch.setattr(demo, "walk_and_wave", _no_work)
    assert main(["demo", "-o", str(tmp_path / "demo")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"cannot write {tmp_path / 'demo' / 'decouple.gif'}: it is a FIFO" in err, err
    assert [p.name for p in (tmp_path / "demo").iterdir()] == ["decouple.gif"]
