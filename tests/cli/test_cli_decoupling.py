"""The decoupling commands as a user runs them, on the demo's walk and walk-plus-wave files."""

import subprocess
import sys

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.decoupling.algebra import decompose
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.procedural import walk_and_wave

ARM = ["UpperArm_R", "LowerArm_R", "Hand_R"]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("decouple")
    pair = walk_and_wave(seconds=3.0)
    em.write_bvh(pair.walk, folder / "walk.bvh")
    em.write_bvh(pair.waving, folder / "wave.bvh")
    slower = walk_and_wave(seconds=2.0, speed=0.8).walk
    em.write_bvh(slower, folder / "slow.bvh")
    return folder


def same_rotation(a, b):
    return np.abs(np.sum(a * b, axis=-1))


def test_decouple_writes_both_components_and_the_activity(files, capsys):
    assert main(["decouple", str(files / "wave.bvh"), "-o", str(files / "w")]) == 0
    out = capsys.readouterr().out
    assert "UpperArm_R" in out and "mean activity per joint" in out
    wave = em.read_bvh(files / "wave.bvh")
    body, expressive = em.read_bvh(files / "w_body.bvh"), em.read_bvh(files / "w_expressive.bvh")
    assert body.n_frames == expressive.n_frames == wave.n_frames
    activity = np.loadtxt(files / "w_activity.csv", delimiter=",", skiprows=1)
    names = wave.skeleton.names
    assert activity.shape == (wave.n_frames, len(names))
    assert activity[:, names.index("UpperArm_R")].mean() > 0.9 > 0.1 > activity[:, names.index("UpperArm_L")].mean()
    # Decoupled again, the body-mechanics file has nothing expressive left on the arm.
    assert decompose(body, BodyModel.load()).activity[:, names.index("UpperArm_R")].mean() < 0.1


def test_modulate_by_one_is_the_input_and_zero_is_the_body(files):
    assert main(["modulate", str(files / "wave.bvh"), "--scale", "1", "-o", str(files / "m1.bvh")]) == 0
    zero = ["modulate", str(files / "wave.bvh"), "--scale", "0", "--no-foot-lock", "-o", str(files / "m0.bvh")]
    assert main(zero) == 0
    wave = em.read_bvh(files / "wave.bvh")
    np.testing.assert_allclose(same_rotation(em.read_bvh(files / "m1.bvh").rotations, wave.rotations), 1.0, atol=1e-9)
    main(["decouple", str(files / "wave.bvh"), "-o", str(files / "w")])
    np.testing.assert_allclose(
        same_rotation(em.read_bvh(files / "m0.bvh").rotations, em.read_bvh(files / "w_body.bvh").rotations),
        1.0,
        atol=1e-9,
    )


def test_mix_lays_the_wave_on_another_walk(files):
    assert (
        main(
            [
                "mix",
                "--body",
                str(files / "slow.bvh"),
                "--expressive",
                str(files / "wave.bvh"),
                "--align",
                "resample",
                "-o",
                str(files / "mixed.bvh"),
            ]
        )
        == 0
    )
    mixed, slow = em.read_bvh(files / "mixed.bvh"), em.read_bvh(files / "slow.bvh")
    assert mixed.n_frames == slow.n_frames
    np.testing.assert_array_equal(mixed.translations, slow.translations)  # root trajectory of the body source
    activity = decompose(mixed, BodyModel.load()).activity
    upper_arm = mixed.skeleton.index("UpperArm_R")
    assert activity[:, upper_arm].mean() > 0.9


def test_blend_and_naive_blend(files):
    for extra in (["--expressive-window", "40:50"], ["--naive"]):
        assert (
            main(
                [
                    "blend",
                    str(files / "walk.bvh"),
                    str(files / "wave.bvh"),
                    "--body-window",
                    "20:35",
                    *extra,
                    "-o",
                    str(files / "b.bvh"),
                ]
            )
            == 0
        )
        blended = em.read_bvh(files / "b.bvh")
        assert blended.n_frames == 20 + em.read_bvh(files / "wave.bvh").n_frames


def test_calibrate_writes_a_calibrated_model(files):
    assert main(["calibrate", str(files / "walk.bvh"), str(files / "slow.bvh"), "-o", str(files / "cal.npz")]) == 0
    calibrated = BodyModel.load(files / "cal.npz")
    assert calibrated.calibration is not None and calibrated.calibration.shape == (22, 4)
    assert main(["decouple", str(files / "wave.bvh"), "--model", str(files / "cal.npz"), "-o", str(files / "c")]) == 0
    assert (
        main(
            [
                "modulate",
                str(files / "wave.bvh"),
                "--scale",
                "1.5",
                "--calibrate",
                str(files / "walk.bvh"),
                "-o",
                str(files / "c15.bvh"),
            ]
        )
        == 0
    )


def test_train_writes_a_loadable_model(files):
    out = files / "tiny.npz"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "expressive_mocap.cli",
            "train",
            str(files / "walk.bvh"),
            str(files / "slow.bvh"),
            str(files / "wave.bvh"),
            "--unlabelled",
            str(files / "wave.bvh"),
            "--hidden",
            "6",
            "--regression-hidden",
            "6",
            "--max-iter",
            "5",
            "-o",
            str(out),
        ],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stderr
    assert "fine_tuned" in result.stdout and "iteration" not in result.stdout  # progress on stderr
    model = BodyModel.load(out)
    assert model.settings.hidden == 6 and model.report.fine_tuned.test_mse is not None


def test_render_decoupled_and_modulated(files):
    for flag in ("--decoupled", "--modulated"):
        assert main(["render", str(files / "wave.bvh"), flag, "--poses", "2", "-o", str(files / "r.png")]) == 0
        assert (files / "r.png").read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize(
    "args, words",
    [
        (["mix", "--body", "WALK", "--expressive", "OTHER", "-o", "x.bvh"], "this body model was trained on"),
        (["decouple", "OTHER", "-o", "x"], "22-joint skeleton"),
        (["blend", "WALK", "WALK", "--body-window", "9:3", "-o", "x.bvh"], "START <= END"),
        (["decouple", "WALK", "--model", "missing.npz", "-o", "x"], "cannot read the model file"),
    ],
)
def test_bad_input_is_one_line(files, mixed_path, tmp_path, args, words):
    args = [str(files / "walk.bvh") if a == "WALK" else str(mixed_path) if a == "OTHER" else a for a in args]
    result = subprocess.run(
        [sys.executable, "-m", "expressive_mocap.cli", *args], capture_output=True, text=True, cwd=tmp_path
    )
    assert result.returncode != 0 and "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1 and words in result.stderr, result.stderr
    assert not list(tmp_path.iterdir())


def test_a_model_no_better_than_the_mean_pose_is_refused_or_written_with_a_warning(files, capsys):
    args = [
        "train",
        str(files / "walk.bvh"),
        str(files / "slow.bvh"),
        "--hidden",
        "20",
        "--regression-hidden",
        "20",
        "--max-iter",
        "2",
        "-q",
    ]
    out = files / "poor.npz"
    assert main([*args, "-o", str(out)]) == 1
    captured = capsys.readouterr()
    assert not out.exists()
    assert (
        captured.err.count("\n") == 1
        and "no better than the mean training pose" in captured.err
        and "--allow-poor" in captured.err
    )
    assert captured.out.count("fine_tuned") == 1  # the report once, on stdout
    assert main([*args, "-o", str(out), "--allow-poor"]) == 0
    assert "warning:" in capsys.readouterr().err and out.exists()
    # Using it says so too, in one line.
    assert main(["decouple", str(files / "wave.bvh"), "--model", str(out), "-o", str(files / "poor")]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert warned == [f"expressive-mocap: warning: {out}: a poor model: " + warned[0].split("a poor model: ", 1)[1]]
    assert "decompositions are unreliable" in warned[0]


def test_training_shows_progress_within_each_stage(files, capsys):
    assert (
        main(
            [
                "train",
                str(files / "walk.bvh"),
                str(files / "slow.bvh"),
                str(files / "wave.bvh"),
                "--hidden",
                "6",
                "--regression-hidden",
                "6",
                "--max-iter",
                "8",
                "--allow-poor",
                "-o",
                str(files / "p.npz"),
            ]
        )
        == 0
    )
    err = capsys.readouterr().err
    for stage in ("autoencoder H=6 round 1/4", "regression", "fine-tuning"):
        assert any(line.startswith(f"{stage}: ") and "iterations, loss" in line for line in err.splitlines()), err


@pytest.mark.parametrize("command", ["decouple", "modulate", "calibrate", "mix"])
def test_a_clip_of_another_skeleton_is_named_with_what_to_do(command, files, mixed_path, capsys):
    args = {
        "decouple": ["decouple", str(mixed_path), "-o", str(files / "x")],
        "modulate": ["modulate", str(mixed_path), "--scale", "2", "-o", str(files / "x.bvh")],
        "calibrate": ["calibrate", str(mixed_path), "-o", str(files / "x.npz")],
        "mix": ["mix", "--body", str(files / "walk.bvh"), "--expressive", str(mixed_path), "-o", str(files / "x.bvh")],
    }[command]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(
        f"expressive-mocap: error: {mixed_path}: this body model was trained on"
    )
    assert "`expressive-mocap train`" in err and "`calibrate`" in err


def test_a_model_file_given_to_calibrate_says_which_option_takes_it(files, capsys):
    assert main(["calibrate", str(files / "walk.bvh"), "-o", str(files / "cal2.npz")]) == 0
    capsys.readouterr()
    assert (
        main(
            [
                "modulate",
                str(files / "wave.bvh"),
                "--scale",
                "2",
                "--calibrate",
                str(files / "cal2.npz"),
                "-o",
                str(files / "m.bvh"),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "a model file" in err and "goes to --model" in err
