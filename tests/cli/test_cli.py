"""The command line as a user runs it: real output files, one-line errors, no tracebacks."""

import subprocess
import sys

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.cli import main


def run(*args):
    """Run the installed command in a subprocess, as a user would."""
    return subprocess.run(
        [sys.executable, "-m", "expressive_mocap.cli", *map(str, args)], capture_output=True, text=True
    )


def test_info_reports_layout_and_rest_height(mixed_path, capsys):
    assert main(["info", str(mixed_path)]) == 0
    out = capsys.readouterr().out
    assert "9 (+3 End Sites)" in out and "4 at 30 fps" in out
    assert "1 joint x 0 (none)" in out and "1 joint x 2 (Yposition Xrotation)" in out
    joints, sites = em.read_bvh(mixed_path).skeleton.rest_positions()  # forward kinematics of the rest pose
    height = np.ptp(np.concatenate([joints[:, 1], sites[:, 1]]))
    assert f"rest pose height {height:.4g}" in out


def test_positions_npz_matches_fk(tmp_path, mixed_path):
    out = tmp_path / "p.npz"
    assert main(["positions", str(mixed_path), "-o", str(out)]) == 0
    motion = em.read_bvh(mixed_path)
    with np.load(out, allow_pickle=False) as saved:
        world_rot, world_pos = motion.fk()
        np.testing.assert_array_equal(saved["positions"], world_pos)
        np.testing.assert_array_equal(saved["rotations"], world_rot)
        assert saved["joints"].tolist() == list(motion.skeleton.names)
        assert saved["parents"].tolist() == motion.skeleton.parents.tolist()
        assert saved["positions"].shape == (4, 9, 3)


def test_convert_resamples_scales_and_reorders(tmp_path, mixed_path):
    out = tmp_path / "c.bvh"
    assert main(["convert", str(mixed_path), "-o", str(out), "--fps", "60", "--scale", "0.01", "--order", "xyz"]) == 0
    original, converted = em.read_bvh(mixed_path), em.read_bvh(out)
    assert converted.fps == pytest.approx(60.0) and converted.n_frames == 7
    assert "Xrotation Yrotation Zrotation" in out.read_text()
    # Every other frame is an original one, to the file's rounded frame time (0.0333333 s, not 1/30).
    np.testing.assert_allclose(converted.positions()[::2], original.positions() * 0.01, atol=1e-5)


def test_render_writes_png_and_gif(tmp_path, mixed_path):
    for name in ["r.png", "r.gif"]:
        assert main(["render", str(mixed_path), str(mixed_path), "-o", str(tmp_path / name)]) == 0
    assert (tmp_path / "r.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "r.gif").read_bytes()[:3] == b"GIF"


def test_demo_runs_without_data(tmp_path):
    result = run("demo", "-o", tmp_path / "demo")
    assert result.returncode == 0, result.stderr
    walk = em.read_bvh(tmp_path / "demo" / "walk.bvh")
    waving = em.read_bvh(tmp_path / "demo" / "walk_wave.bvh")
    assert walk.skeleton.n_joints == 22 and walk.n_frames == 121
    # The Bandai skeleton: its rest pose is a crouch 99.78 cm tall, the actor 140.9 cm.
    assert "rest pose height 99.78" in result.stdout and "actor height 140.9 cm" in result.stdout
    # The toe joints (inside the feet) touch down 4.35 cm above the floor, as in the real clips,
    # and the hips travel speed x duration along +Z.
    positions = walk.positions()
    assert positions[:, [16, 17, 20, 21], 1].min() == pytest.approx(4.35)
    assert positions[-1, 1, 2] - positions[0, 1, 2] == pytest.approx(480.0)
    assert "hips travelled 4.80 m in 4.00 s" in result.stdout
    assert "footsteps: 7 (3 left, 4 right), cadence 1.88 steps/s" in result.stdout
    assert "joints that differ: UpperArm_R, LowerArm_R, Hand_R" in result.stdout
    np.testing.assert_array_equal(
        np.delete(waving.rotations, [11, 12, 13], axis=1), np.delete(walk.rotations, [11, 12, 13], axis=1)
    )
    assert (tmp_path / "demo" / "walk.png").exists() and (tmp_path / "demo" / "walk.gif").exists()


@pytest.mark.parametrize(
    "args, words",
    [
        (["info", "missing.bvh"], "cannot read"),
        (["convert", "BROKEN", "-o", "x.bvh"], "line"),
        (["convert", "GOOD", "-o", "no/such/folder/x.bvh"], "does not exist"),
        (["convert", "GOOD", "-o", "x.bvh", "--fps", "-3"], "must be positive"),
        (["convert", "GOOD", "-o", "x.bvh", "--order", "XXY"], "invalid choice"),
        (["positions", "GOOD"], "required"),
        (["render", "GOOD", "-o", "x.jpg"], ".png or .gif"),
        (["frobnicate"], "invalid choice"),
    ],
)
def test_bad_input_is_one_line_and_nonzero(tmp_path, mixed_path, args, words):
    broken = tmp_path / "broken.bvh"
    broken.write_bytes(mixed_path.read_bytes().replace(b"93.0", b"9x3"))
    args = [str(mixed_path) if a == "GOOD" else str(broken) if a == "BROKEN" else a for a in args]
    result = subprocess.run(
        [sys.executable, "-m", "expressive_mocap.cli", *args], capture_output=True, text=True, cwd=tmp_path
    )
    assert result.returncode != 0
    assert "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert words in result.stderr
    assert not (tmp_path / "x.bvh").exists()


def test_help_reads_well():
    result = run("--help")
    assert result.returncode == 0
    for command in ["info", "positions", "convert", "render", "demo"]:
        assert command in result.stdout
    assert "--order" in run("convert", "--help").stdout


def test_positions_csv_is_csv_and_other_extensions_are_refused(tmp_path, mixed_path, capsys):
    motion = em.read_bvh(mixed_path)
    assert main(["positions", str(mixed_path), "-o", str(tmp_path / "p.csv")]) == 0
    table = np.loadtxt(tmp_path / "p.csv", delimiter=",", skiprows=1, ndmin=2)
    header = (tmp_path / "p.csv").read_text().splitlines()[0].split(",")
    assert header[:4] == [
        "time",
        f"{motion.skeleton.names[0]}_x",
        f"{motion.skeleton.names[0]}_y",
        f"{motion.skeleton.names[0]}_z",
    ]
    np.testing.assert_allclose(table[:, 0], np.arange(motion.n_frames) * motion.frame_time, rtol=1e-8)
    np.testing.assert_allclose(table[:, 1:].reshape(motion.n_frames, -1, 3), motion.positions(), rtol=1e-8, atol=1e-9)
    capsys.readouterr()
    assert main(["positions", str(mixed_path), "-o", str(tmp_path / "p.txt")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and ".npz" in err and ".csv" in err and not (tmp_path / "p.txt").exists()


def test_decouple_output_ending_in_bvh_is_a_prefix(tmp_path, capsys):
    from expressive_mocap.procedural import walk_and_wave

    em.write_bvh(walk_and_wave(seconds=1.0).waving, tmp_path / "wave.bvh")
    assert main(["decouple", str(tmp_path / "wave.bvh"), "-o", str(tmp_path / "out.bvh")]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "out_activity.csv",
        "out_body.bvh",
        "out_expressive.bvh",
        "wave.bvh",
    ]


def test_the_command_groups_list_every_command_and_a_command_line_loads_only_its_own():
    import argparse

    from expressive_mocap.cli import COMMANDS, build_parser

    def commands(parser):
        return list(next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices)

    assert commands(build_parser()) == [name for names in COMMANDS.values() for name in names]
    for names in COMMANDS.values():
        assert commands(build_parser(names[0])) == list(names)
    # The methods' code is not loaded by a preprocess command line (a third of start-up time).
    code = (
        "import sys; from expressive_mocap.cli import _command_of, build_parser; "
        "build_parser(_command_of(['--backend', 'numpy', 'preprocess', 'SRC', '-o', 'OUT'])); "
        "print(sorted(sys.modules))"
    )
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert "expressive_mocap.dataset.run" in loaded
    assert "expressive_mocap.exaggeration" not in loaded and "expressive_mocap.decoupling.training" not in loaded


def _modules_loaded_by(*words: str) -> set[str]:
    """The modules a command line loads, in a fresh interpreter (the command run to its end)."""
    code = (
        "import sys; from expressive_mocap.cli import main\n"
        f"try: main({list(words)!r})\n"
        "except SystemExit: pass\n"
        "print(' '.join(sorted(sys.modules)), file=sys.stderr)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    return set(done.stderr.split())


def test_the_quick_commands_load_only_what_they_use(mixed_path):
    """Start-up time is imports: --version loads no NumPy and no command's code, info on a file
    reads it without the methods, SciPy or the pictures' code (before, scipy.signal alone took a
    second of every command line through the exaggeration models' gesture cycles)."""
    version = _modules_loaded_by("--version")
    assert "numpy" not in version and "expressive_mocap.bvh" not in version
    assert not {m for m in version if m.startswith("expressive_mocap.cli.") and m != "expressive_mocap.cli.common"}
    info = _modules_loaded_by("info", str(mixed_path))
    assert "expressive_mocap.bvh.reader" in info  # it did read the file
    if em.rust_available():  # its number block is checked by the Rust kernel, without NumPy
        assert "numpy" not in info
    for heavy in (
        "scipy",
        "matplotlib",
        "expressive_mocap.decoupling",
        "expressive_mocap.exaggeration",
        "expressive_mocap.viz",
        "expressive_mocap.dataset",
        "expressive_mocap.reference",
    ):
        assert heavy not in info
