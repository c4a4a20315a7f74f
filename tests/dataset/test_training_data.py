"""Reading a preprocessed dataset for training: statistics, labels, splits, windows, augmented
batches. Most tests run on a small preprocess of real dataset-2 clips
(Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0), one of them in a subfolder."""

from __future__ import annotations

import json
import os
import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from expressive_mocap.dataset import (
    Augment,
    Labels,
    Normaliser,
    WindowReader,
    Windows,
    clip_windows,
    compute_stats,
    load_dataset,
    split,
    window_batches,
)
from expressive_mocap.dataset.augment import rotate_window_kinds
from expressive_mocap.dataset.representations import KINDS as FORMS
from expressive_mocap.dataset.representations import encode
from expressive_mocap.errors import ArgumentError, DatasetError
from expressive_mocap.rotations import quat
from training_clips import training_dataset


@pytest.fixture(scope="module")
def folder(bandai2_dir, tmp_path_factory):
    return training_dataset(bandai2_dir, tmp_path_factory.mktemp("training"))


@pytest.fixture(scope="module")
def ds(folder):
    return load_dataset(folder)


# Windows


@pytest.mark.parametrize("padding", ["drop", "edge", "zero"])
@pytest.mark.parametrize("length,stride", [(64, 64), (64, 17), (300, 50)])
def test_windows_stay_in_their_clip_and_equal_the_direct_slices(ds, padding, length, stride):
    windows = Windows(ds, length, stride, padding)
    covered = np.zeros(len(ds.positions), dtype=bool)
    for i in range(len(windows)):
        c = windows.clip[i]
        clip = ds[int(c)].positions
        begin, end = ds.offsets[c], ds.offsets[c + 1]
        rows = windows.rows(i)
        assert begin <= rows.min() and rows.max() < end  # never across a clip's boundary
        offset = int(windows.offset[i])
        expected = clip[offset : offset + length]
        missing = length - len(expected)
        assert windows.valid[i] == len(expected)
        if missing:
            assert padding != "drop"
            fill = expected[-1:] if padding == "edge" else np.zeros_like(expected[:1])
            expected = np.concatenate([expected, np.repeat(fill, missing, axis=0)])
        np.testing.assert_array_equal(windows.read(ds.positions, i), expected)
        covered[begin + offset : begin + offset + len(clip[offset : offset + length])] = True
    frames = np.diff(ds.offsets)
    if padding != "drop" and stride <= length:
        assert covered.all()  # every frame of every clip is in some window
    per_clip = np.bincount(windows.clip, minlength=len(ds))
    if padding == "drop":
        np.testing.assert_array_equal(per_clip, np.where(frames >= length, (frames - length) // stride + 1, 0))


def test_unpadded_windows_are_views_of_the_memory_map(ds):
    windows = Windows(ds, 32, 8)
    for i in (0, len(windows) // 2, len(windows) - 1):
        window = windows.read(ds.positions, i)
        assert isinstance(ds.positions, np.memmap) and np.shares_memory(window, ds.positions)
        assert not window.flags.owndata
    clip = ds[2].rotations
    strided = clip_windows(clip, 32, 5)
    assert np.shares_memory(strided, ds.rotations) and strided.shape[1:] == (32, *clip.shape[1:])
    assert len(strided) == (len(clip) - 32) // 5 + 1
    for k in (0, len(strided) - 1):
        np.testing.assert_array_equal(strided[k], clip[5 * k : 5 * k + 32])
    assert len(clip_windows(clip[:10], 32)) == 0


def test_a_batch_holds_the_windows_it_names(ds):
    windows = Windows(ds, 48, 20, "edge")
    reader = WindowReader(ds, windows)
    picked = np.random.default_rng(3).choice(len(windows), 40, replace=False)
    batch = reader.read(picked)
    assert sorted(batch["window"]) == sorted(picked)
    assert np.all(np.diff(windows.start[batch["window"]]) >= 0)  # gathered in row order
    for j, w in enumerate(batch["window"]):
        for kind in ds.kinds:
            expected = windows.read(ds.arrays[kind], int(w)).astype(np.float32)
            np.testing.assert_array_equal(batch[kind][j], expected)
        assert batch["clip"][j] == windows.clip[w] and batch["start"][j] == windows.offset[w]
        assert batch["valid"][j] == windows.valid[w]


# Splits


def _records(names, mirrored=False):
    clips = []
    for n in names:
        clips.append({"name": n})
        if mirrored:
            clips.append({"name": f"{n}@mirrored", "mirror_of": n})
    return SimpleNamespace(clips=clips, names=[c["name"] for c in clips])


NAMES = [f"dataset-2_{c}_{s}_{t:03d}" for c in ("walk", "run", "walk-left") for s in "abcdefg" for t in range(1, 6)]


@pytest.mark.parametrize("by", ["performance", "clip", "take", "style", "content"])
def test_splits_are_disjoint_cover_all_and_keep_mirrored_copies_together(by):
    data = _records(NAMES, mirrored=True)
    labels = Labels.from_names(data)
    parts = split(data, by=by, seed=7, labels=labels)
    joined = np.concatenate(list(parts.values()))
    assert sorted(joined) == list(range(len(data.clips)))  # disjoint and covering
    where = {int(i): name for name, idx in parts.items() for i in idx}
    for i, record in enumerate(data.clips):
        if "mirror_of" in record:
            assert where[i] == where[data.names.index(record["mirror_of"])]
    if by != "clip":
        value = (
            (lambda i: (labels.values["content"][i], labels.values["style"][i]))
            if by == "performance"
            else (lambda i: labels.values[by][i])
        )
        for name, idx in parts.items():  # a group never straddles two splits
            for other, rest in parts.items():
                if other != name:
                    assert not {value(i) for i in idx} & {value(i) for i in rest}
    assert {k: list(v) for k, v in split(data, by=by, seed=7, labels=labels).items()} == {
        k: list(v) for k, v in parts.items()
    }


def test_hash_splits_are_stable_under_adding_clips_and_follow_the_seed():
    old, new = NAMES[:60], NAMES  # more clips later
    before, after = split(old, "clip", seed=1, method="hash"), split(new, "clip", seed=1, method="hash")
    placed = {new[i]: name for name, idx in after.items() for i in idx}
    for name, idx in before.items():
        assert all(placed[old[i]] == name for i in idx)
    sizes = {k: len(v) for k, v in after.items()}
    assert abs(sizes["train"] / len(new) - 0.8) < 0.1 and sizes["val"] and sizes["test"]
    assert any(not np.array_equal(split(new, "clip", seed=2, method="hash")[k], after[k]) for k in after)


@pytest.mark.parametrize("groups", [3, 10, 11, 57])
def test_rank_splits_give_each_split_its_share_of_groups(groups):
    names = [f"clip{i:03d}" for i in range(groups)]
    parts = split(names, "clip", fractions=(0.8, 0.1, 0.1), seed=4)
    sizes = [len(parts[k]) for k in ("train", "val", "test")]
    assert sum(sizes) == groups and min(sizes) >= 1  # nothing lost, no split left empty
    assert all(abs(size - f * groups) < 1 + 1e-9 for size, f in zip(sizes[1:], (0.1, 0.1)) if groups >= 10)
    same = {k: list(v) for k, v in parts.items()}
    assert {k: list(v) for k, v in split(names, "clip", fractions=(0.8, 0.1, 0.1), seed=4).items()} == same
    assert any({k: list(v) for k, v in split(names, "clip", seed=s).items()} != same for s in range(5, 10))
    grown = split(names + ["extra"], "clip", fractions=(0.8, 0.1, 0.1), seed=4)
    placed = {i: k for k, idx in grown.items() for i in idx}
    moved = sum(placed[i] != k for k, idx in parts.items() for i in idx)
    assert moved <= 2  # one more group shifts at most the two boundaries


def test_the_default_split_keeps_every_take_of_a_performance_together():
    """Takes of one dataset, content and style are repetitions: never in two splits, whatever the
    seed; other datasets' clips of the same content and style are other performances."""
    names = NAMES + [n.replace("dataset-2_", "dataset-1_") for n in NAMES[:35]]
    data = _records(names, mirrored=True)
    for seed in range(6):
        parts = split(data, seed=seed)
        assert {k: list(v) for k, v in parts.items()} == {
            k: list(v) for k, v in split(data, "performance", seed=seed, labels=Labels.from_names(data)).items()
        }
        where: dict[str, str] = {}
        for name, idx in parts.items():
            assert len(idx)
            for i in idx:
                performance = data.names[i].removesuffix("@mirrored").rsplit("_", 1)[0]
                assert where.setdefault(performance, name) == name
        assert len(where) == 21 + 7 and len(set(where.values())) == 3
    originals = split(data, seed=0, mirrored=False)
    assert all(not data.names[i].endswith("@mirrored") for idx in originals.values() for i in idx)
    assert {k: [data.names[i] for i in v] for k, v in originals.items()} == {
        k: [data.names[i] for i in v if not data.names[i].endswith("@mirrored")] for k, v in split(data).items()
    }


def test_names_that_are_not_bandai_names_split_alone_with_a_warning():
    names = [f"s{a}_{e}_t{t}" for a in "12" for e in ("happy", "sad") for t in range(4)] + ["dataset-2_run_normal_001"]
    with pytest.warns(UserWarning, match=r"16 of 17 clip names \(e.g. 's1_happy_t0'\).*by='clip'"):
        parts = split(names, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert {k: list(v) for k, v in split(names, "clip", seed=0).items()} == {k: list(v) for k, v in parts.items()}
        labels = Labels.from_names(names[:16], "s{actor}_{emotion}_t{take}")
        grouped = split(names[:16], seed=0, labels=labels)
        for idx in grouped.values():  # four takes of one actor and emotion go together
            assert len(idx) % 4 == 0 and len({names[i].rsplit("_", 1)[0] for i in idx}) == len(idx) // 4
        by_content = split(NAMES, "content", seed=0)  # Bandai labels read from the names
    assert [len({NAMES[i].split("_")[1] for i in idx}) for idx in by_content.values()] == [1, 1, 1]
    with pytest.raises(ArgumentError, match="no such field"):
        split(names[:16], "performance", labels=Labels.from_names(names[:16], "s{actor}_{emotion}_{rest}"))
    with pytest.raises(DatasetError, match="'s1_happy_t0'.*splitting by 'content'"):
        split(names, "content")
    with pytest.raises(ArgumentError, match="argument `by`"):
        split(names, ["clip"])  # type: ignore[arg-type]


def test_held_out_groups_are_exact_and_checked():
    labels = Labels.from_names(NAMES)
    parts = split(NAMES, by="style", held_out={"test": ["g"], "val": ["f"]}, labels=labels)
    assert {labels.values["style"][i] for i in parts["test"]} == {"g"}
    assert {labels.values["style"][i] for i in parts["val"]} == {"f"}
    assert len(parts["train"]) == len(NAMES) * 5 // 7
    with pytest.raises(ArgumentError, match="'elderly'"):
        split(NAMES, by="style", held_out={"test": ["elderly"]}, labels=labels)
    with pytest.raises(ArgumentError, match="labels"):
        split(NAMES, by="actor")


# Labels


def test_labels_parse_the_real_names(ds):
    labels = Labels.from_names(ds)  # the Bandai pattern by default; one name has a folder
    by_name = {n: {f: labels.values[f][i] for f in labels.fields} for i, n in enumerate(ds.names)}
    assert by_name["sub/dataset-2_walk-turn-left_active_002"] == {
        "dataset": "2",
        "content": "walk-turn-left",
        "style": "active",
        "take": "002",
    }
    assert labels.vocab["content"] == ["run", "walk", "walk-turn-left"]
    assert labels.vocab["style"] == ["active", "elderly", "normal"]
    for f in labels.fields:  # codes are places in the sorted vocabulary
        assert labels.decode(f, labels.codes[f]) == labels.values[f]
    mirrored = Labels.from_names(["a/dataset-2_walk_normal_001@mirrored"])
    assert mirrored.values["take"] == ["001"]


def test_names_that_do_not_match_are_named_or_skipped():
    names = ["dataset-2_walk_normal_001", "notes_take", "dataset-1_run_angry_003"]
    with pytest.raises(DatasetError, match="'notes_take'.*dataset-\\{dataset\\}"):
        Labels.from_names(names)
    labels = Labels.from_names(names, skip=True)
    assert labels.skipped == [1] and list(labels.codes["dataset"]) == [1, -1, 0]
    custom = Labels.from_names(["s01_happy_walk", "s02_sad_run"], "s{actor}_{emotion}_{action}")
    assert custom.values["actor"] == ["01", "02"] and custom.values["action"] == ["walk", "run"]


def test_labels_from_a_csv(tmp_path):
    path = tmp_path / "labels.csv"
    path.write_text("clip,actor,emotion\nwalk_a,ann,happy\nwalk_b,bob,sad\n")
    labels = Labels.from_csv(path, ["walk_b", "walk_a", "walk_a@mirrored"])
    assert labels.values == {"actor": ["bob", "ann", "ann"], "emotion": ["sad", "happy", "happy"]}
    assert list(labels.codes["actor"]) == [1, 0, 0]
    with pytest.raises(DatasetError, match="'walk_c'"):
        Labels.from_csv(path, ["walk_c"])
    assert Labels.from_csv(path, ["walk_c"], skip=True).skipped == [0]


# Statistics


def test_statistics_computed_in_chunks_equal_numpys(ds):
    stats = compute_stats(ds, chunk_rows=97)
    assert set(stats) == {"positions", "rotations"}  # float kinds only
    for kind, entry in stats.items():
        values = np.asarray(ds.arrays[kind], dtype=np.float64)
        np.testing.assert_allclose(entry["mean"], values.mean(axis=0), rtol=1e-10, atol=1e-9)
        std = values.std(axis=0)
        np.testing.assert_allclose(entry["std"], np.where(std < 1e-8, 1.0, std), rtol=1e-9, atol=1e-9)
        assert entry["frames"] == len(values)
    normaliser = Normaliser(stats)
    x = np.asarray(ds.positions[:500])
    z = normaliser.normalise("positions", x)
    assert z.dtype == np.float32 and np.all(np.abs(z.mean(axis=0)) < 5)
    np.testing.assert_allclose(normaliser.denormalise("positions", z), x, rtol=1e-5, atol=1e-3)


def test_the_manifests_statistics_are_used_when_there(folder, tmp_path):
    copy = tmp_path / "ds"
    copy.mkdir()
    for f in folder.iterdir():
        if f.is_file():
            os.link(f, copy / f.name)  # same files, same times
    manifest = json.loads((copy / "manifest.json").read_text())
    manifest["stats"] = {"positions": {"mean": np.full((22, 3), 5.0).tolist(), "std": [[2.0] * 3] * 22, "frames": 1}}
    (copy / "manifest.json").unlink()
    (copy / "manifest.json").write_text(json.dumps(manifest))
    normaliser = Normaliser.of(load_dataset(copy))
    assert normaliser.frames["positions"] == 1 and normaliser.frames["rotations"] > 1  # recorded / computed
    np.testing.assert_array_equal(normaliser.normalise("positions", np.full((4, 22, 3), 9.0)), 2.0)
    with pytest.raises(KeyError, match="contacts"):
        normaliser.normalise("contacts", np.zeros((1, 2)))


@pytest.mark.parametrize("bad", [float("inf"), 1e-300, float("nan"), 0.0])
def test_statistics_that_would_not_normalise_are_refused(folder, tmp_path, bad):
    """A manifest whose std is inf normalised every batch to zeros, one of 1e-300 to inf: refused,
    naming the kind, the channel and the value."""
    copy = tmp_path / "ds"
    copy.mkdir()
    for f in folder.iterdir():
        if f.is_file():
            os.link(f, copy / f.name)
    manifest = json.loads((copy / "manifest.json").read_text())
    std = np.ones((22, 3))
    std[4, 1] = bad
    manifest["stats"] = {"positions": {"mean": np.zeros((22, 3)).tolist(), "std": std.tolist(), "frames": 1}}
    (copy / "manifest.json").unlink()
    (copy / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(ArgumentError, match=r"stats of 'positions': std of channel \(4, 1\) is"):
        Normaliser.of(load_dataset(copy))


# Augmentation


def test_rotation_keeps_bones_and_turns_positions_and_the_root_together(ds):
    reader = WindowReader(ds, Windows(ds, 64, 32), augment=Augment(rotate=True))
    plain = WindowReader(ds, Windows(ds, 64, 32))
    picked = np.arange(0, len(reader.windows), 3)
    turned, original = reader.read(picked, 0), plain.read(picked)
    assert np.ptp(turned["angle"]) > 1.0
    parents = ds.skeleton["parents"]
    for kind_parent in range(1, len(parents)):
        p = parents[kind_parent]
        bone = np.linalg.norm(turned["positions"][..., kind_parent, :] - turned["positions"][..., p, :], axis=-1)
        was = np.linalg.norm(original["positions"][..., kind_parent, :] - original["positions"][..., p, :], axis=-1)
        np.testing.assert_allclose(bone, was, rtol=1e-4, atol=1e-3)
    # The hips hang off the root: world offset = root rotation * local offset, before and after.
    root_q = original["rotations"][..., 0, :].astype(np.float64)
    local = quat.rotate(quat.conjugate(root_q), original["positions"][..., 1, :] - original["positions"][..., 0, :])
    after = quat.rotate(turned["rotations"][..., 0, :].astype(np.float64), local)
    np.testing.assert_allclose(after, turned["positions"][..., 1, :] - turned["positions"][..., 0, :], atol=0.05)
    heights = turned["positions"] @ np.array([0.0, 1.0, 0.0])  # Y up: heights unchanged
    np.testing.assert_allclose(heights, original["positions"][..., 1], atol=1e-3)
    np.testing.assert_array_equal(turned["contacts"], original["contacts"])


@pytest.mark.parametrize("form", list(FORMS))
def test_rotating_by_theta_then_minus_theta_is_the_identity(ds, form):
    rng = np.random.default_rng(5)
    positions = np.asarray(ds.positions[:320], dtype=np.float32).reshape(5, 64, 22, 3)
    quats = np.asarray(ds.rotations[:320], dtype=np.float64).reshape(5, 64, 22, 4)
    spelled = "euler:ZXY" if form == "euler" else form
    manifest = {"options": {"rotations": spelled, "positions": "world"}, "up": [0, 1, 0]}
    batch = {"positions": positions.copy(), "rotations": encode(quats, form).astype(np.float32)}
    start = {k: v.copy() for k, v in batch.items()}
    theta = rng.uniform(-np.pi, np.pi, 5)
    rotate_window_kinds(batch, theta, manifest, [0])
    assert not np.allclose(batch["positions"], start["positions"], atol=1.0)
    np.testing.assert_array_equal(batch["rotations"][:, :, 1:], start["rotations"][:, :, 1:])  # only the root
    rotate_window_kinds(batch, -theta, manifest, [0])
    np.testing.assert_allclose(batch["positions"], start["positions"], atol=2e-3)
    np.testing.assert_allclose(batch["rotations"], start["rotations"], atol=2e-3 if form == "euler" else 2e-5)


def test_heading_frame_kinds_do_not_turn_and_undefined_kinds_are_refused():
    manifest = {"options": {"positions": "heading"}, "up": [0, 1, 0]}
    batch = {"positions": np.ones((2, 3, 4, 3), np.float32), "root_velocity": np.ones((2, 3, 4), np.float32)}
    rotate_window_kinds(batch, np.array([1.0, 2.0]), manifest, [0])
    assert np.all(batch["positions"] == 1) and np.all(batch["root_velocity"] == 1)
    world = {"velocities": np.ones((2, 3, 4, 3), np.float32)}
    rotate_window_kinds(world, np.array([np.pi / 2, np.pi]), {"up": [0, 0, 2]}, [0])  # Z up
    np.testing.assert_allclose(world["velocities"][0, 0, 0], [-1, 1, 1], atol=1e-6)
    np.testing.assert_allclose(world["velocities"][1, 0, 0], [-1, -1, 1], atol=1e-6)
    with pytest.raises(ArgumentError, match="body"):
        rotate_window_kinds({"body": np.zeros((1, 1, 1, 4))}, np.ones(1), manifest, [0])


def test_rotations_turn_about_their_own_worlds_up():
    """Harmonised positions are Y up; a Z-up file's rotations are not, and turn about Z."""
    manifest = {"options": {"positions": "heading"}, "up": [0, 1, 0], "rotations_up": [0, 0, 1]}
    q = Rotation.random(6, random_state=2).as_quat().reshape(1, 1, 6, 4)
    batch = {"rotations": q.astype(np.float32), "angular_velocities": np.ones((1, 1, 6, 3), np.float32)}
    rotate_window_kinds(batch, np.array([0.7]), manifest, [0])
    expected = (Rotation.from_euler("z", 0.7) * Rotation.from_quat(q[0, 0, 0])).as_quat()
    assert abs(abs(float(np.dot(batch["rotations"][0, 0, 0], expected))) - 1) < 1e-6
    np.testing.assert_allclose(batch["rotations"][0, 0, 1:], q[0, 0, 1:], atol=1e-7)  # only the root turns
    np.testing.assert_allclose(
        batch["angular_velocities"][0, 0, 0], Rotation.from_euler("z", 0.7).apply([1, 1, 1]), atol=1e-6
    )


def test_speed_factor_one_is_the_identity_and_two_skips_every_other_frame(ds):
    windows = Windows(ds, 40, 40)
    picked = np.arange(len(windows))
    plain = WindowReader(ds, windows).read(picked)
    same = WindowReader(ds, windows, augment=Augment(speed=(1.0, 1.0))).read(picked, 0)
    for kind in ds.kinds:
        np.testing.assert_array_equal(same[kind], plain[kind])
    double = WindowReader(ds, windows, augment=Augment(speed=(2.0, 2.0))).read(picked, 0)
    for j, w in enumerate(double["window"]):
        rows = np.minimum(windows.start[w] + 2 * np.arange(40), windows.end[w] - 1)
        np.testing.assert_allclose(double["positions"][j], ds.positions[rows], atol=1e-4)
        np.testing.assert_allclose(np.abs(double["rotations"][j]), np.abs(ds.rotations[rows]), atol=1e-5)
        assert double["valid"][j] == min(40, (windows.end[w] - windows.start[w] - 1) // 2 + 1)


def test_speed_interpolates_between_frames_and_scales_rates():
    from expressive_mocap.dataset.augment import interpolate, scale_rates

    a, b = np.zeros((1, 2, 3), np.float32), np.full((1, 2, 3), 4.0, np.float32)
    mid = interpolate("velocities", a, b, np.array([[0.0, 0.25]]), {})
    np.testing.assert_allclose(mid[0, :, 0], [0.0, 1.0])
    speeds = np.array([2.0])
    assert scale_rates("velocities", b, speeds)[0, 0, 0] == 8 and scale_rates("accelerations", b, speeds)[0, 0, 0] == 16
    features = scale_rates("features", np.ones((1, 1, 19), np.float32), speeds)[0, 0]
    assert list(features[:6]) == [2] * 6 and list(features[8:10]) == [0.5, 0.5] and features[10] == 1


def test_normalised_noisy_batches_are_reproducible_from_the_seed(ds):
    augment = Augment(rotate=0.5, speed=(0.8, 1.25), noise=0.05)

    def run(seed, epoch):
        loader = window_batches(ds, 32, 16, batch_size=16, augment=augment, normalise=True, seed=seed)
        return list(loader.epoch(epoch))

    first, again, other = run(3, 1), run(3, 1), run(4, 1)
    assert len(first) == len(window_batches(ds, 32, 16, batch_size=16))
    for x, y in zip(first, again):
        for kind in ds.kinds:
            np.testing.assert_array_equal(x[kind], y[kind])
    assert not np.array_equal(first[0]["positions"], other[0]["positions"])
    windows = np.concatenate([b["window"] for b in first])
    assert sorted(windows) == list(range(len(windows)))  # an epoch reads every window once
    loader = window_batches(ds, 32, 16, batch_size=16, normalise=True, shuffle=False)
    clean = next(iter(loader))
    normaliser = loader.reader.normaliser
    assert normaliser is not None
    back = normaliser.denormalise("positions", clean["positions"])
    np.testing.assert_allclose(
        back, WindowReader(ds, loader.reader.windows).read(clean["window"])["positions"], atol=1e-3
    )
    noisy = WindowReader(ds, loader.reader.windows, augment=Augment(noise=0.1), normaliser=normaliser)
    diff = noisy.read(clean["window"], 1)["positions"] - clean["positions"]
    assert abs(diff.mean()) < 0.01 and abs(diff.std() - 0.1) < 0.01


def test_batches_carry_labels_and_a_split(ds):
    labels = Labels.from_names(ds)
    parts = split(ds, by="content", held_out={"test": ["run"]}, labels=labels)
    loader = window_batches(ds, 32, 32, batch_size=8, clips=parts["test"], labels=labels)
    seen = set()
    for batch in loader:
        assert set(batch["clip"]) <= set(parts["test"])
        assert labels.decode("content", batch["labels"]["content"]) == ["run"] * len(batch["clip"])
        seen |= set(batch["clip"])
    assert seen == set(parts["test"])
