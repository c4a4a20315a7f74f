"""Same input, same dataset: a clip's stored values do not depend on which clips share its batch,
on ``batch_mb``, or on a run stopped and resumed; each clip's values are what it gives alone.

The property test draws option sets (rotation form, position frame, frame rate, mirror images,
the shipped model, the canonical body) and batch sizes from fixed seeds, stops each run at
random batches and resumes it, and compares every array byte for byte with an uninterrupted
run. The normalisation statistics are float64 sums taken batch by batch, so they may differ in
the last bits: means to a relative 1e-9, variances to 1e-9 of the mean square they are taken from."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.dataset.derive import resampled, unwrap_by_clip
from expressive_mocap.motion import Motion
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.canonical import many_onto_canonical, onto_canonical
from expressive_mocap.skeletons.mirror import mirror, mirror_many

FORMS = ("quaternion", "6d", "matrix", "axis-angle", "euler:XYZ")
FRAMES = ("world", "root", "heading", "clip")
MOTION_KINDS = ("positions", "rotations", "features", "contacts", "velocities", "root_velocity", "heading")


def turned(motion: Motion, degrees: float, axis: str = "Y") -> Motion:
    """``motion`` turned about the vertical (or ``axis``): its root's rotation and place."""
    turn = quat.about(axis, degrees)
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[:, 0] = quat.mul(turn, rotations[:, 0])
    translations[:, 0] = quat.rotate(turn, translations[:, 0])
    return Motion(motion.skeleton, rotations, translations, motion.frame_time)


def arm_twisted(motion: Motion, degrees: float = 150.0) -> Motion:
    """``motion`` with its left upper arm turned about itself and the forearm turned back: the
    same positions, rotations whose twist is not to be trusted (as some networks write them)."""
    jmap = find_joint_map(motion.skeleton)
    arm, forearm = jmap["left_upper_arm"], jmap["left_forearm"]
    bone = motion.skeleton.offsets[forearm] / np.linalg.norm(motion.skeleton.offsets[forearm])
    twist = quat.exp(bone * np.radians(degrees))
    rotations = motion.rotations.copy()
    rotations[:, arm] = quat.mul(rotations[:, arm], twist)
    rotations[:, forearm] = quat.mul(quat.conjugate(twist), rotations[:, forearm])
    return Motion(motion.skeleton, rotations, motion.translations, motion.frame_time)


@pytest.fixture(scope="module")
def one_skeleton(tmp_path_factory) -> Path:
    """Clips of the canonical hierarchy with different offsets (actors), rates and headings:
    one walks along -Z, so its heading crosses +-180 degrees."""
    folder = tmp_path_factory.mktemp("one_skeleton")
    walk = procedural_walk(3.0)
    clips = {
        "a_walk": walk,
        "b_small_actor_60fps": procedural_walk(2.0, fps=60.0).scaled(0.8),
        "c_wave_tall": procedural_walk(2.5, wave="right").scaled(1.15),
        "d_walk_back": turned(walk, 180.0),
        "e_short": procedural_walk(1.0).scaled(0.9),
    }
    for name, motion in clips.items():
        em.write_bvh(motion, folder / f"{name}.bvh")
    return folder


@pytest.fixture(scope="module")
def many_skeletons(tmp_path_factory) -> Path:
    """Clips of several rigs for --canonical, one of them twice, the second with an arm whose
    rotations twist arbitrarily."""
    folder = tmp_path_factory.mktemp("many_skeletons")
    for rig in ("bandai", "cmu", "game", "mixamo"):
        em.write_bvh(synthetic_walk(rig, seconds=2.0).motion, folder / f"walk_{rig}.bvh")
    em.write_bvh(arm_twisted(synthetic_walk("cmu", seconds=2.0).motion), folder / "walk_cmu_twisted.bvh")
    em.write_bvh(turned(synthetic_walk("mixamo", seconds=1.5).motion, 180.0), folder / "walk_mixamo_back.bvh")
    return folder


def draw_options(rng: np.random.Generator) -> dict:
    """A random option set of ``preprocess``."""
    kinds = [k for k in MOTION_KINDS if rng.random() < 0.6] or ["positions"]
    model = rng.random() < 0.4
    if model:
        kinds += ["activity", "body"]
    return {
        "keep": tuple(kinds),
        "model": "" if model else None,
        "canonical": bool(rng.random() < 0.5),
        "rotations": FORMS[rng.integers(len(FORMS))],
        "positions": FRAMES[rng.integers(len(FRAMES))],
        "fps": [None, 24.0, 30.0, 45.0][rng.integers(4)],
        "mirror": bool(rng.random() < 0.5),
    }


def resumed(src: Path, out: Path, options: dict, rng: np.random.Generator) -> int:
    """``preprocess`` in small batches, stopped after a random number of batches and resumed
    until finished; returns the number of runs."""
    batch_mb = float(rng.uniform(0.02, 0.4))
    for runs in range(1, 100):
        summary = preprocess(
            src, out, batch_mb=batch_mb, max_batches=int(rng.integers(1, 3)), progress=False, **options
        )
        if summary.finished:
            return runs
    raise AssertionError("never finished")


def assert_same_dataset(a: Path, b: Path) -> None:
    """Every array of ``a`` and ``b`` byte for byte, their manifests equal but for the times of
    writing, the normalisation statistics among them (each clip summed row after row, the clips
    added in the dataset's order, whatever the batches)."""
    first, second = load_dataset(a, mmap=False), load_dataset(b, mmap=False)
    assert list(first.arrays) == list(second.arrays)
    for kind in first.arrays:
        assert first.arrays[kind].dtype == second.arrays[kind].dtype, kind
        assert first.arrays[kind].tobytes() == second.arrays[kind].tobytes(), kind
    assert np.array_equal(first.offsets, second.offsets)
    one, two = (json.loads((p / "manifest.json").read_text()) for p in (a, b))
    for key in ("created", "files"):
        one.pop(key), two.pop(key)  # times of writing
    assert one == two


def clip_values(dataset, name: str) -> dict[str, np.ndarray]:
    record = next(c for c in dataset.manifest["clips"] if c["name"] == name)
    start, count = record["start"], record["frames"]
    return {kind: np.asarray(array[start : start + count]) for kind, array in dataset.arrays.items()}


@pytest.mark.parametrize("seed", range(8))
def test_batches_and_resumes_give_the_same_dataset(seed, one_skeleton, many_skeletons, tmp_path):
    rng = np.random.default_rng(seed)
    options = draw_options(rng)
    src = many_skeletons if options["canonical"] else one_skeleton
    whole = preprocess(src, tmp_path / "whole", progress=False, **options)
    assert whole.finished and whole.clips_failed == 0, whole.failures
    runs = resumed(src, tmp_path / "resumed", options, rng)
    assert runs > 1  # it was stopped and resumed
    assert_same_dataset(tmp_path / "whole", tmp_path / "resumed")
    # Each clip (and its mirror image) holds what it gives in a dataset of its own, at the same rate.
    dataset = load_dataset(tmp_path / "whole")
    for path in sorted(src.glob("*.bvh"))[seed % 2 :: 2]:
        alone = tmp_path / "alone" / path.stem
        alone.mkdir(parents=True)
        (alone / path.name).symlink_to(path)
        # At the dataset's rate: --canonical resamples clips of several rates to the one most share.
        at_its_rate = {**options, "fps": dataset.manifest["options"]["fps"]}
        preprocess(alone, tmp_path / "alone_out" / path.stem, progress=False, **at_its_rate)
        own = load_dataset(tmp_path / "alone_out" / path.stem)
        for name in [c["name"] for c in own.manifest["clips"]]:
            mine, together = clip_values(own, name), clip_values(dataset, name)
            for kind in mine:
                assert mine[kind].tobytes() == together[kind].tobytes(), (name, kind, options)


def test_features_of_a_resampled_clip_are_those_of_the_clip_resampled(one_skeleton, tmp_path):
    """With --fps, each clip's features and contacts are the public functions' of the resampled
    clip (with its own actor's height), whatever other clips share its batch."""
    preprocess(one_skeleton, tmp_path / "out", keep="features,contacts", fps=30.0, progress=False)
    dataset = load_dataset(tmp_path / "out")
    for path in sorted(one_skeleton.glob("*.bvh")):
        motion = resampled(em.read_bvh(path), 30.0)
        stored = clip_values(dataset, path.stem)
        expected = em.dynamic_features(motion)
        np.testing.assert_allclose(stored["features"], expected, atol=2e-5, err_msg=path.stem)
        assert np.array_equal(stored["contacts"].astype(bool), em.foot_contacts(motion)), path.stem


def test_heading_is_unwrapped_within_each_clip_only():
    angles = np.array([3.0, -3.1, 3.1, 3.0, -3.0, -3.1, 3.1])  # two clips: frames 0-2 and 3-6
    out = unwrap_by_clip(angles, np.array([0, 3]))
    assert out[0] == 3.0 and out[3] == 3.0  # each clip starts where its first frame is
    assert np.all(np.abs(np.diff(out[:3])) < np.pi) and np.all(np.abs(np.diff(out[3:])) < np.pi)
    assert np.allclose(out[3:], np.unwrap(angles[3:]))
    assert np.array_equal(unwrap_by_clip(angles, np.array([0, 3, 7])), out)  # a clip of no frames last
    # Bit for bit each clip's own, after a clip that turned many times (taking the whole turns
    # back off a run's unwrap changed the last bits of a resumed run's yaw rate).
    rng = np.random.default_rng(5)
    spinning = np.angle(np.exp(1j * np.linspace(0.0, 40.0 * np.pi, 500)))
    wobbling = np.angle(np.exp(1j * (np.pi + np.cumsum(rng.normal(0.0, 0.3, 300)))))
    together = unwrap_by_clip(np.concatenate([spinning, wobbling]), np.array([0, 500]))
    assert np.array_equal(together[500:], np.unwrap(wobbling))


def test_a_clip_retargeted_with_others_is_retargeted_as_alone():
    """A clip whose arm twists arbitrarily, retargeted with a clip of the same skeleton that does
    not: each gets its own twist reading (before, the first clip's was used for both: 150
    degrees off at the arm)."""
    walk = synthetic_walk("cmu", seconds=2.0).motion
    twisted = arm_twisted(walk)
    for order in ([walk, twisted], [twisted, walk]):
        for motion, (together, _) in zip(order, many_onto_canonical(order)):
            alone, _ = onto_canonical(motion)
            turn = quat.angle(quat.mul(alone.rotations, quat.conjugate(together.rotations)))
            assert np.degrees(turn).max() < 1e-6
            assert np.abs(alone.translations - together.translations).max() < 1e-9


def test_clips_mirrored_together_are_mirrored_as_alone():
    """Clips of one hierarchy with different offsets, headings and up axes, mirrored in one call,
    are each their own mirror image (before, the longest clip's rig was used for all: a clip
    captured Z-up was mirrored across the wrong plane)."""
    z_up = turned(procedural_walk(1.0), 90.0, axis="X")
    clips = [procedural_walk(2.0), z_up, turned(procedural_walk(1.5), 90.0).scaled(1.2)]
    for motion, image in zip(clips, mirror_many(clips)):
        alone = mirror(motion)
        assert np.abs(alone.rotations - image.rotations).max() < 1e-12
        assert np.abs(alone.translations - image.translations).max() < 1e-9


@pytest.mark.real_data
def test_real_clips_give_the_same_dataset_whatever_the_batches(bandai2_dir, other_dir, tmp_path):
    """Dataset-2 clips of several actors and real files of other rigs, resampled, mirrored, on the
    canonical body with the shipped model: one run and a run of small batches stopped and
    resumed give the same bytes (before: features, contacts, heading, arm rotations and
    activity of many clips differed)."""
    src = tmp_path / "src"
    src.mkdir()
    styles = ("normal", "active", "elderly", "feminine", "masculine", "youthful")
    picked = [
        bandai2_dir / f"dataset-2_{action}_{style}_001.bvh" for action in ("walk", "wave-left-hand") for style in styles
    ]
    picked += [other_dir / name for name in ("m21_walk.bvh", "m21_female-walk.bvh", "dme_demo_3d_1.bvh")]
    for path in picked:
        (src / path.name).symlink_to(path)
    options = {
        "keep": ("positions", "rotations", "features", "contacts", "heading", "root_velocity", "activity"),
        "model": "",
        "canonical": True,
        "fps": 24.0,
        "mirror": True,
        "positions": "heading",
        "rotations": "6d",
    }
    whole = preprocess(src, tmp_path / "whole", progress=False, **options)
    assert whole.finished and whole.clips_failed == 0, whole.failures
    assert resumed(src, tmp_path / "resumed", options, np.random.default_rng(26)) > 2
    assert_same_dataset(tmp_path / "whole", tmp_path / "resumed")
