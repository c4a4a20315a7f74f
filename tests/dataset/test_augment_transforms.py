"""Per-sample augmentation (expressive_mocap.dataset.transforms): draws fixed by seed, epoch and
window alone, probabilities that hold, mirroring that reads the mirror image's rows, rotations
that keep bones and turn velocities, dropout that zeroes exactly what it says. On four real
dataset-2 clips preprocessed with their mirror images (Bandai-Namco-Research-Motiondataset,
CC BY-NC 4.0)."""

from __future__ import annotations

import os

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from expressive_mocap.dataset import (
    Augment,
    Compose,
    JointDropout,
    Labels,
    Mirror,
    Noise,
    RandomRotation,
    Speed,
    WindowDataset,
    WindowReader,
    Windows,
    load_dataset,
    preprocess,
    split,
    window_batches,
)
from expressive_mocap.errors import ArgumentError
from training_clips import training_dataset

CLIPS = ["dataset-2_walk_normal_001", "dataset-2_run_elderly_002", "dataset-2_wave-left-hand_active_001"]
KEEP = "positions,rotations,velocities,root_velocity,contacts"
EVERYTHING = Compose(
    [RandomRotation(p=0.5), Mirror(p=0.5), Speed((0.8, 1.25), p=0.3), Noise(0.05, p=0.4), JointDropout(0.2, p=0.5)]
)


@pytest.fixture(scope="module")
def folder(bandai2_dir, tmp_path_factory):
    root = tmp_path_factory.mktemp("mirrored")
    (root / "src").mkdir()
    for name in CLIPS:
        os.symlink(bandai2_dir / f"{name}.bvh", root / "src" / f"{name}.bvh")
    summary = preprocess(root / "src", root / "ds", keep=KEEP, mirror=True, progress=False)
    assert summary.clips_ok == 2 * len(CLIPS)
    return root / "ds"


@pytest.fixture(scope="module")
def ds(folder):
    return load_dataset(folder)


def _per_window(batches) -> dict[int, dict]:
    """Each window's row of every array of ``batches`` (dicts of ``[B, ...]``), by window index."""
    rows: dict[int, dict] = {}
    for batch in batches:
        for j, w in enumerate(batch["window"]):
            rows[int(w)] = {k: v[j] for k, v in batch.items() if k != "labels"}
    return rows


def _same_rows(a: dict, b: dict) -> None:
    assert a.keys() == b.keys()
    for w in a:
        for key in a[w]:
            np.testing.assert_allclose(a[w][key], b[w][key], rtol=0, atol=1e-5, err_msg=f"window {w}, {key}")


def test_draws_depend_on_seed_epoch_and_window_alone(ds, folder):
    """The same windows read in batches of 5 or of 64, shuffled, one by one through a
    WindowDataset or as one list: the same draws and the same values."""
    small = _per_window(window_batches(ds, 32, 16, batch_size=5, augment=EVERYTHING, normalise=True, seed=3).epoch(2))
    large = _per_window(window_batches(ds, 32, 16, batch_size=64, augment=EVERYTHING, normalise=True, seed=3).epoch(2))
    _same_rows(small, large)
    items = WindowDataset(folder, 32, 16, augment=EVERYTHING, normalise=True, seed=3)
    items.set_epoch(2)
    picked = [7, 0, len(items) - 1, 3]
    for w, item, listed in zip(picked, items.__getitems__(picked), (items[i] for i in picked)):
        for key, value in item.items():
            if key != "labels":
                np.testing.assert_allclose(value, small[w][key], rtol=0, atol=1e-5, err_msg=key)
                np.testing.assert_allclose(listed[key], small[w][key], rtol=0, atol=1e-5, err_msg=key)
    drawn = np.array([[r["angle"], r["speed"], r["mirrored"], r["dropped"].sum()] for r in small.values()])
    for p, column in ((0.5, 0), (0.3, 1), (0.5, 2), (0.5, 3)):
        share = np.mean(drawn[:, column] != (1 if column == 1 else 0))
        assert 0 < share < 1, (p, share)  # some windows get it, some not
    other_epoch = _per_window(window_batches(ds, 32, 16, batch_size=64, augment=EVERYTHING, seed=3).epoch(1))
    other_seed = _per_window(window_batches(ds, 32, 16, batch_size=64, augment=EVERYTHING, seed=4).epoch(2))
    for other in (other_epoch, other_seed):
        assert any(other[w]["angle"] != small[w]["angle"] for w in small)


def test_probabilities_and_ranges_hold_over_many_windows():
    names = [f"j{i}" for i in range(22)]
    compose = Compose(
        [RandomRotation(0.5, p=0.25), Mirror(p=0.5), Speed((0.5, 2.0), p=0.75), Noise(p=0.1), JointDropout(0.2, p=0.4)]
    )
    draws = compose.draw(9, 0, np.arange(40_000), JointDropout(joints=["j0", 3]).droppable(names))
    rotated, sped = draws.angle != 0, draws.speed != 1
    for got, p in ((rotated, 0.25), (draws.mirrored, 0.5), (sped, 0.75), (draws.noised, 0.1)):
        assert abs(got.mean() - p) < 0.01
    assert np.all(np.abs(draws.angle) <= 0.5) and abs(np.mean(draws.angle[rotated] > 0) - 0.5) < 0.02
    assert np.all((draws.speed >= 0.5) & (draws.speed <= 2.0))
    assert abs(np.median(np.log(draws.speed[sped]))) < 0.02  # log-uniform: as often slower as faster
    assert not draws.dropped[:, [1, 2, *range(4, 22)]].any()  # only the joints allowed
    assert abs(draws.dropped[:, 0].mean() - 0.4 * 0.2) < 0.01
    pairs = [(rotated, draws.mirrored), (draws.mirrored, sped), (sped, draws.noised)]
    for a, b in pairs:  # independent streams
        assert abs(np.mean(a & b) - a.mean() * b.mean()) < 0.01
    again = compose.draw(9, 0, np.arange(39_990, 40_010), np.ones(22, bool))
    np.testing.assert_array_equal(again.angle[:10], draws.angle[39_990:])


def test_p0_leaves_windows_as_read_and_p1_always_applies(ds):
    windows = Windows(ds, 40, 20)
    picked = np.arange(len(windows))
    plain = WindowReader(ds, windows).read(picked)
    never = Compose(
        [RandomRotation(p=0), Mirror(p=0), Speed((1.0, 1.0)), Noise(0.5, p=0), JointDropout(0.5, p=0)]
    )  # active (a speed of 1 on every window), every other transform at p = 0
    none = WindowReader(ds, windows, augment=never).read(picked, 5)
    for kind in ds.kinds:
        np.testing.assert_array_equal(none[kind], plain[kind])
    assert not none["angle"].any() and not none["mirrored"].any() and not none["dropped"].any()
    assert np.all(none["speed"] == 1) and not none["noised"].any()
    always = Compose(
        [RandomRotation(p=1), Mirror(p=1), Speed((0.8, 0.9), p=1), Noise(0.01, p=1), JointDropout(0.5, p=1)]
    )
    full = WindowReader(ds, windows, augment=always).read(picked, 5)
    assert np.all(full["angle"] != 0) and full["mirrored"].all() and np.all(full["speed"] < 1)
    assert full["noised"].all() and full["dropped"].any(axis=1).all()


def test_mirroring_reads_the_same_window_of_the_mirror_image(ds):
    windows = Windows(ds, 48, 24, "edge")
    labels = Labels.from_names(ds)
    reader = WindowReader(ds, windows, augment=Mirror(p=0.5), labels=labels, seed=1)
    batch = reader.read(np.arange(len(windows)))
    assert 0 < batch["mirrored"].sum() < len(windows)
    for j, w in enumerate(batch["window"]):
        own = int(windows.clip[w])
        name = ds.names[own]
        partner = name.removesuffix("@mirrored") if name.endswith("@mirrored") else f"{name}@mirrored"
        read = ds.names.index(partner) if batch["mirrored"][j] else own
        assert batch["clip"][j] == read and batch["start"][j] == windows.offset[w]
        rows = np.minimum(ds.offsets[read] + windows.offset[w] + np.arange(48), ds.offsets[read + 1] - 1)
        for kind in ds.kinds:
            np.testing.assert_array_equal(batch[kind][j], np.asarray(ds.arrays[kind][rows], np.float32))
        assert {f: int(c[j]) for f, c in batch["labels"].items()} == {f: int(c[own]) for f, c in labels.codes.items()}
    originals = split(ds, "clip", fractions={"train": 1.0}, mirrored=False)["train"]
    assert [ds.names[i] for i in originals] == sorted(CLIPS)
    mirrored = WindowReader(ds, Windows(ds, 48, 24, clips=originals), augment=Mirror(p=1)).read([0, 1])
    assert all(ds.names[c].endswith("@mirrored") for c in mirrored["clip"])


def test_mirroring_needs_the_mirror_images(bandai2_dir, tmp_path):
    plain = load_dataset(training_dataset(bandai2_dir, tmp_path))
    with pytest.raises(ArgumentError, match=r"argument `augment`: Mirror .* has none \(preprocess with --mirror\)"):
        WindowReader(plain, Windows(plain, 32, 32), augment=[Mirror()])
    WindowReader(plain, Windows(plain, 32, 32), augment=[Mirror(p=0), RandomRotation()])  # p = 0: not needed


def test_rotation_keeps_bones_turns_positions_and_velocities_alike_and_not_the_heading_frame(ds):
    windows = Windows(ds, 32, 16)
    picked = np.arange(len(windows))
    plain = WindowReader(ds, windows).read(picked)
    turned = WindowReader(ds, windows, augment=RandomRotation(p=0.5), seed=2).read(picked)
    angle = turned["angle"]
    assert 0 < np.count_nonzero(angle) < len(angle)
    same = angle == 0
    for kind in ds.kinds:
        np.testing.assert_array_equal(turned[kind][same], plain[kind][same])
    parents = ds.skeleton["parents"]
    child = [j for j, p in enumerate(parents) if p >= 0]
    bones = np.linalg.norm(
        turned["positions"][..., child, :] - turned["positions"][..., [parents[j] for j in child], :], axis=-1
    )
    was = np.linalg.norm(
        plain["positions"][..., child, :] - plain["positions"][..., [parents[j] for j in child], :], axis=-1
    )
    np.testing.assert_allclose(bones, was, rtol=1e-5, atol=1e-3)
    up = np.asarray(ds.manifest["up"], dtype=float)
    for j in np.flatnonzero(~same):
        r = Rotation.from_rotvec(up / np.linalg.norm(up) * angle[j])
        for kind in ("positions", "velocities"):  # velocities turn exactly as the positions they are of
            expected = r.apply(plain[kind][j].reshape(-1, 3).astype(np.float64)).reshape(plain[kind][j].shape)
            np.testing.assert_allclose(turned[kind][j], expected, rtol=1e-5, atol=2e-3)
        # root_velocity is the hips' velocity in its own heading frame: a turn of the world leaves it
        np.testing.assert_array_equal(turned["root_velocity"][j], plain["root_velocity"][j])
        hips = Rotation.from_quat(turned["rotations"][j, :, 0].astype(np.float64))
        np.testing.assert_allclose(
            (hips * Rotation.from_quat(plain["rotations"][j, :, 0].astype(np.float64)).inv()).as_rotvec(),
            np.tile(r.as_rotvec(), (32, 1)),
            atol=1e-5,
        )


def test_speed_resamples_only_the_windows_it_applies_to(ds):
    windows = Windows(ds, 40, 20)
    picked = np.arange(len(windows))
    plain = WindowReader(ds, windows).read(picked)
    sped = WindowReader(ds, windows, augment=Speed((2.0, 2.0), p=0.5), seed=1).read(picked)
    assert set(np.unique(sped["speed"])) == {1.0, 2.0}
    for j, w in enumerate(sped["window"]):
        if sped["speed"][j] == 1:
            np.testing.assert_array_equal(sped["rotations"][j], plain["rotations"][j])
            np.testing.assert_array_equal(sped["velocities"][j], plain["velocities"][j])
        else:
            rows = np.minimum(windows.start[w] + 2 * np.arange(40), windows.end[w] - 1)
            np.testing.assert_allclose(sped["positions"][j], ds.positions[rows], atol=1e-4)
            np.testing.assert_allclose(sped["velocities"][j], 2 * ds.velocities[rows], rtol=1e-5, atol=1e-3)


def test_joint_dropout_zeroes_exactly_the_dropped_joints_and_nothing_else(ds):
    windows = Windows(ds, 32, 16)
    picked = np.arange(len(windows))
    noise = Noise(0.1, p=0.5)
    kept = WindowReader(ds, windows, augment=[noise], normaliser=None, seed=6).read(picked, 1)
    dropped = WindowReader(ds, windows, augment=[JointDropout(0.3, p=0.5), noise], seed=6).read(picked, 1)
    mask = dropped["dropped"]
    assert mask.shape == (len(picked), 22) and 0 < mask.any(axis=1).mean() < 1
    assert abs(mask[mask.any(axis=1)].mean() - 0.3) < 0.1
    np.testing.assert_array_equal(dropped["noised"], kept["noised"])  # dropout draws nothing of the noise's
    for kind in ("positions", "rotations", "velocities"):
        expanded = np.broadcast_to(mask[:, None, :, None], kept[kind].shape)
        assert np.all(dropped[kind][expanded] == 0)
        np.testing.assert_array_equal(dropped[kind][~expanded], kept[kind][~expanded])
    for kind in ("root_velocity", "contacts"):  # no joint axis: untouched
        np.testing.assert_array_equal(dropped[kind], kept[kind])
    hands = WindowReader(ds, windows, augment=JointDropout(1.0, joints=["Hand_L", "Hand_R"])).read(picked)
    names = ds.skeleton["names"]
    assert [names[j] for j in np.flatnonzero(hands["dropped"].all(axis=0))] == ["Hand_L", "Hand_R"]
    assert hands["dropped"].sum() == 2 * len(picked)
    with pytest.raises(ArgumentError, match="argument `joints`: no joint 'Tail'"):
        WindowReader(ds, windows, augment=JointDropout(joints=["Tail"]))


def test_the_augment_shorthand_is_the_same_transforms_on_every_window(ds):
    short = window_batches(ds, 32, 16, batch_size=8, augment=Augment(rotate=0.5, speed=(0.8, 1.25), noise=0.01))
    long = window_batches(
        ds, 32, 16, batch_size=8, augment=Compose([RandomRotation(0.5), Speed((0.8, 1.25)), Noise(0.01)])
    )
    _same_rows(_per_window(short.epoch(0)), _per_window(long.epoch(0)))
    first = next(iter(short.epoch(0)))
    assert np.all(first["angle"] != 0) and first["noised"].all() and not first["mirrored"].any()


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda: Speed((1.25, 0.8)), r"argument `factors`: \(low, high\) with 0 < low <= high"),
        (lambda: Mirror(p=1.5), r"argument `p`: a probability in \[0, 1\], got 1.5"),
        (lambda: RandomRotation(7.0), r"argument `max_angle`: radians in \[0, pi\]"),
        (lambda: Noise(-0.1), "argument `std`"),
        (lambda: JointDropout(2.0), "argument `rate`"),
        (lambda: Compose([Mirror(), Mirror(p=0.2)]), "Mirror given twice"),
        (lambda: Compose([Augment(rotate=True)]), "argument `transforms`"),
        (lambda: Augment(speed=(2.0, 1.0)), "argument `speed`"),
    ],
)
def test_bad_transforms_are_refused_naming_the_argument(make, message):
    with pytest.raises(ArgumentError, match=message):
        make()


def test_reading_with_a_generator_says_where_draws_come_from(ds):
    reader = WindowReader(ds, Windows(ds, 32, 32), augment=RandomRotation())
    with pytest.raises(ArgumentError, match="argument `epoch`: a whole number .* seed, the epoch and each window"):
        reader.read([0], np.random.default_rng(0))  # type: ignore[arg-type]
    with pytest.raises(ArgumentError, match="argument `augment`"):
        WindowReader(ds, Windows(ds, 32, 32), augment="rotate")  # type: ignore[arg-type]


def test_noise_is_each_windows_own_and_only_where_drawn(ds):
    loader = window_batches(ds, 32, 16, batch_size=1000, augment=Noise(0.1, p=0.5), normalise=True, seed=2)
    noisy = next(iter(loader.epoch(0)))
    clean = WindowReader(ds, loader.reader.windows, normaliser=loader.reader.normaliser).read(noisy["window"])
    hit = noisy["noised"]
    assert 0 < hit.mean() < 1
    np.testing.assert_array_equal(noisy["contacts"], clean["contacts"])
    for kind in ("positions", "rotations", "root_velocity"):
        diff = (noisy[kind] - clean[kind]).reshape(len(hit), -1)
        assert not diff[~hit].any()
        assert abs(diff[hit].std() - 0.1) < 0.005 and abs(diff[hit].mean()) < 0.005
        pairs = np.corrcoef(diff[hit][:6])[np.triu_indices(min(6, int(hit.sum())), 1)]
        assert np.all(np.abs(pairs) < 0.2)  # not the same noise on every window
