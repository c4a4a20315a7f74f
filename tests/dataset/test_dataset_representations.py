"""``preprocess`` writing model-ready arrays: rotation forms, position frames, velocities,
resampling, mirrored copies and normalisation statistics, each checked against an independent
computation from the world positions and rotations of a plain run (or of the files).

Real clips: eight of Bandai-Namco-Research-Motiondataset dataset-2 (CC BY-NC 4.0), spread over
the archive; synthetic walks for other skeletons and axes.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap.body import find_joint_map
from expressive_mocap.body.conventions import _changed
from expressive_mocap.cli import main
from expressive_mocap.dataset import load_dataset, preprocess, representations
from expressive_mocap.dataset.heading import HeadingFrame, from_heading, turn_by_yaw
from expressive_mocap.errors import ArgumentError, DatasetError
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.mirror import _linear, _planes_of, _through_positions, mirror, partners
from expressive_mocap.skeletons.synthetic import RIGS

ALL = "positions,rotations,contacts,velocities,accelerations,root_velocity,angular_velocities"


def run(src, out, **kw):
    kw.setdefault("progress", False)
    return preprocess(src, out, **kw)


@pytest.fixture(scope="module")
def clips(bandai2_dir, tmp_path_factory):
    """Eight real clips (links in a folder of their own)."""
    folder = tmp_path_factory.mktemp("bandai")
    for path in sorted(bandai2_dir.glob("*.bvh"))[::360][:8]:
        (folder / path.name).symlink_to(path)
    return folder


@pytest.fixture(scope="module")
def world(clips, tmp_path_factory):
    """Every kind in world positions and quaternions, in batches of a few clips."""
    out = tmp_path_factory.mktemp("world") / "ds"
    run(clips, out, keep=ALL, batch_mb=4.0)
    return load_dataset(out)


@pytest.fixture(scope="module")
def frame(world, clips):
    """The heading frame of the Bandai skeleton, from the world positions."""
    skeleton = em.read_bvh(next(clips.glob("*.bvh"))).skeleton
    return HeadingFrame.of(skeleton, np.asarray(world.positions[::10], dtype=np.float64))


def per_clip(ds):
    """(name, rows, frame time) of each clip of ``ds``."""
    return [(c["name"], slice(c["start"], c["start"] + c["frames"]), c["frame_time"]) for c in ds.clips]


@pytest.mark.real_data
@pytest.mark.parametrize("form", ["6d", "matrix", "axis-angle", "euler:ZXY", "euler:XYZ"])
def test_each_rotation_form_decodes_to_the_stored_quaternions(clips, world, form, tmp_path):
    run(clips, tmp_path / "ds", keep="rotations", rotations=form)
    ds = load_dataset(tmp_path / "ds")
    kind, _, order = form.partition(":")
    assert ds.rotations.shape == world.rotations.shape[:2] + (representations.KINDS[kind],)
    assert ds.manifest["options"]["rotations"] == form
    decoded = representations.decode(ds.rotations, kind, order or "ZXY")
    expected = representations.decode(world.rotations, "quaternion")
    # The same rotation: |<q, p>| = 1 (q and -q are one rotation), within float32 rounding.
    assert np.abs(np.abs(np.sum(decoded * expected, axis=-1)) - 1).max() < 2e-6
    angle = 2 * np.arccos(np.clip(np.abs(np.sum(decoded * expected, axis=-1)), 0, 1))
    assert angle.max() < (1e-4 if kind == "euler" else 2e-5)  # radians; Euler angles are float32 degrees


@pytest.mark.real_data
def test_heading_positions_put_the_hips_on_the_floor_facing_z_and_come_back(clips, world, frame, tmp_path):
    run(clips, tmp_path / "ds", keep="positions,velocities,accelerations,root_velocity", positions="heading")
    ds = load_dataset(tmp_path / "ds")
    assert ds.manifest["up"] == [0.0, 1.0, 0.0] and ds.manifest["options"]["positions"] == "heading"
    positions, hips = ds.positions, frame.hips
    np.testing.assert_allclose(positions[:, hips, [0, 2]], 0.0, atol=1e-4)  # under the hips
    np.testing.assert_allclose(positions[:, hips, 1], world.positions[:, hips, 1], rtol=1e-6)  # height kept
    # Facing +Z: the left-minus-right lines of hips and shoulders, on the floor and made unit, sum along +X.
    lines = [(positions[:, a] - positions[:, b])[:, [0, 2]] for a, b in frame.pairs]
    left = sum(line / np.linalg.norm(line, axis=-1, keepdims=True) for line in lines)
    left = np.stack([left[:, 0], np.zeros(len(left)), left[:, 1]], axis=-1)
    assert np.all(left[:, 0] > 0) and np.abs(left[:, 2] / left[:, 0]).max() < 1e-4
    # Back to the world through the inverse transform (yaw and origin read from the world positions).
    wp = np.asarray(world.positions, dtype=np.float64)
    yaw, origin = frame.yaw(wp), frame.origin(wp)
    np.testing.assert_allclose(from_heading(positions.astype(np.float64), frame, yaw, origin), wp, atol=2e-3)
    # Velocities: the world's, turned into each frame's heading; the root's yaw rate: the yaw's change.
    for _, rows, dt in per_clip(ds):
        expected = np.gradient(wp[rows], dt, axis=0)
        np.testing.assert_allclose(turn_by_yaw(ds.velocities[rows], yaw[rows]), expected, atol=2e-2)
        accel = np.gradient(expected, dt, axis=0)
        np.testing.assert_allclose(turn_by_yaw(ds.accelerations[rows], yaw[rows]), accel, atol=2.0)
        root = ds.root_velocity[rows]
        np.testing.assert_allclose(turn_by_yaw(root[:, :3], yaw[rows]), expected[:, hips], atol=2e-2)
        np.testing.assert_allclose(root[:, 3], np.gradient(np.unwrap(yaw[rows]), dt), atol=1e-4)


@pytest.mark.real_data
def test_root_and_clip_frames(clips, world, frame, tmp_path):
    run(clips, tmp_path / "root", keep="positions", positions="root")
    run(clips, tmp_path / "clip", keep="positions,velocities", positions="clip")
    root, clip = load_dataset(tmp_path / "root"), load_dataset(tmp_path / "clip")
    wp = np.asarray(world.positions, dtype=np.float64)
    np.testing.assert_allclose(root.positions, wp - wp[:, :1], atol=2e-4)  # Bandai: Y up, facing +Z already
    yaw, origin = frame.yaw(wp), frame.origin(wp)
    for _, rows, dt in per_clip(clip):
        first = np.full(rows.stop - rows.start, rows.start)
        back = from_heading(clip.positions[rows].astype(np.float64), frame, yaw[first], origin[first])
        # One transform for the whole clip (its yaw read here from float32 positions: 1e-5 rad at 5 m).
        np.testing.assert_allclose(back, wp[rows], atol=1e-2)
        np.testing.assert_allclose(clip.velocities[rows], np.gradient(clip.positions[rows], dt, axis=0), atol=1e-2)


@pytest.mark.real_data
@pytest.mark.parametrize("form", ["6d", "matrix"])
def test_the_clip_kernels_forms_are_those_derived_from_a_batch(clips, form, tmp_path):
    # 6D / matrix rotations and world velocities come from the clip kernels as they are stored;
    # with accelerations kept they are derived from the batch's quaternions and positions
    # instead (.derive): the same arrays, bit for bit, and the same statistics.
    run(clips, tmp_path / "kernels", keep="rotations,velocities", rotations=form)
    run(clips, tmp_path / "derived", keep="rotations,velocities,accelerations", rotations=form, batch_mb=4.0)
    kernels, derived = load_dataset(tmp_path / "kernels"), load_dataset(tmp_path / "derived")
    for kind in ("rotations", "velocities"):
        np.testing.assert_array_equal(kernels.arrays[kind], derived.arrays[kind])
        for what in ("mean", "std"):
            np.testing.assert_allclose(
                kernels.manifest["stats"][kind][what], derived.manifest["stats"][kind][what], rtol=1e-9, atol=1e-9
            )
    assert kernels.manifest["up"] == derived.manifest["up"] == [0, 1, 0]


@pytest.mark.real_data
def test_velocities_integrate_back_and_never_span_two_clips(world):
    for _, rows, dt in per_clip(world):
        p, v = world.positions[rows].astype(np.float64), world.velocities[rows].astype(np.float64)
        # Central differences telescope: p[t] + p[t-1] = p[0] + p[1] + 2 dt (v[1] + ... + v[t-1]).
        summed = 2 * dt * np.cumsum(v[1:-1], axis=0)
        np.testing.assert_allclose(p[2:] + p[1:-1], p[0] + p[1] + summed, atol=5e-3)
        np.testing.assert_allclose(p[1] - p[0], v[0] * dt, atol=1e-4)  # one-sided at the ends:
        np.testing.assert_allclose(p[-1] - p[-2], v[-1] * dt, atol=1e-4)  # nothing of the next clip
        np.testing.assert_allclose(world.accelerations[rows], np.gradient(v, dt, axis=0), rtol=1e-5, atol=1e-2)


@pytest.mark.real_data
def test_angular_velocities_agree_with_scipy(world):
    for _, rows, dt in per_clip(world)[:3]:
        q = world.rotations[rows].astype(np.float64)
        ahead, behind = Rotation.from_quat(q[2:].reshape(-1, 4)), Rotation.from_quat(q[:-2].reshape(-1, 4))
        central = (ahead * behind.inv()).as_rotvec().reshape(q[1:-1].shape[:-1] + (3,)) / (2 * dt)
        np.testing.assert_allclose(world.angular_velocities[rows][1:-1], central, atol=2e-3)
        first = (Rotation.from_quat(q[1]) * Rotation.from_quat(q[0]).inv()).as_rotvec() / dt
        np.testing.assert_allclose(world.angular_velocities[rows][0], first, atol=2e-3)


@pytest.mark.real_data
def test_resampling_to_the_same_rate_changes_nothing_and_to_half_takes_every_second_frame(clips, world, tmp_path):
    run(clips, tmp_path / "same", keep="positions,rotations,contacts,velocities", fps=30)
    run(clips, tmp_path / "half", keep="positions,rotations", fps=15)
    same, half = load_dataset(tmp_path / "same"), load_dataset(tmp_path / "half")
    for kind in ("positions", "rotations", "contacts"):
        np.testing.assert_array_equal(same.arrays[kind], world.arrays[kind])
    np.testing.assert_allclose(same.velocities, world.velocities, rtol=1e-5, atol=1e-3)  # 1/30 s, not 0.0333333 s
    for record, (name, rows, _) in zip(half.clips, per_clip(world)):
        assert record["name"] == name and record["fps"] == 15.0 and record["source_fps"] == pytest.approx(30, 1e-5)
        mine = half.clip(name)
        np.testing.assert_array_equal(mine.positions, world.positions[rows][::2])
        np.testing.assert_array_equal(mine.rotations, world.rotations[rows][::2])


@pytest.mark.real_data
def test_resampling_between_frames_is_the_motions_own_resampling(clips, tmp_path):
    run(clips, tmp_path / "ds", keep="positions,rotations", fps=24)
    ds = load_dataset(tmp_path / "ds")
    for path in sorted(clips.glob("*.bvh"))[:3]:
        motion = em.read_bvh(path).resample(fps=24)
        clip = ds.clip(path.stem)
        assert clip.frames == motion.n_frames
        dots = np.abs(np.sum(clip.rotations * motion.rotations, axis=-1))
        assert np.abs(dots - 1).max() < 2e-6
        np.testing.assert_allclose(clip.positions, motion.positions(), atol=2e-3)


def test_a_clip_resampled_past_what_a_motion_may_hold_is_that_clips_failure(tmp_path):
    """Two frames 10^6 s apart at 30 fps would be 3 x 10^7 frames: refused before any is made."""
    walk = synthetic_walk("bandai", seconds=1.0).motion
    (tmp_path / "src").mkdir()
    em.write_bvh(walk, tmp_path / "src" / "walk.bvh")
    em.write_bvh(
        em.Motion(walk.skeleton, walk.rotations[:2], walk.translations[:2], 1e6), tmp_path / "src" / "huge.bvh"
    )
    summary = run(tmp_path / "src", tmp_path / "ds", keep="positions", fps=30)
    assert summary.clips_ok == 1 and summary.clips_failed == 1
    (failure,) = summary.failures
    assert "huge.bvh" in failure["error"] and "cannot be resampled" in failure["error"]
    assert load_dataset(tmp_path / "ds").clips[0]["frames"] == walk.n_frames


@pytest.mark.real_data
def test_mirrored_clips_are_skeletons_mirror_with_their_contacts_swapped(clips, world, tmp_path):
    run(clips, tmp_path / "ds", keep="positions,rotations,contacts,features", mirror=True, batch_mb=8.0)
    ds = load_dataset(tmp_path / "ds")
    assert len(ds) == 2 * len(world) and ds.manifest["options"]["mirror"] is True
    for path in sorted(clips.glob("*.bvh"))[:4]:
        original, image = ds.clip(path.stem), ds.clip(path.stem + "@mirrored")
        assert image.index == original.index + 1 and image.record["mirror_of"] == path.stem
        np.testing.assert_array_equal(original.positions, world.clip(path.stem).positions)
        np.testing.assert_array_equal(image.contacts, original.contacts[:, ::-1])
        motion = em.read_bvh(path)
        mirrored = mirror(motion)
        np.testing.assert_allclose(image.positions, mirrored.positions(), atol=2e-3)
        assert np.abs(np.abs(np.sum(image.rotations * mirrored.rotations, axis=-1)) - 1).max() < 2e-6
        # The stored image mirrored again is the original (translations: the image's own).
        stored = em.Motion(motion.skeleton, image.rotations.astype(np.float64), mirrored.translations, 1 / 30)
        back = mirror(stored)
        assert np.abs(np.abs(np.sum(back.rotations * motion.rotations, axis=-1)) - 1).max() < 2e-6
        np.testing.assert_allclose(back.positions(), motion.positions(), atol=2e-3)
        # Swapping the labels is what the image's own feet say, nearly everywhere.
        assert np.mean(em.foot_contacts(mirrored) == image.contacts) > 0.97


@pytest.mark.parametrize("rig", RIGS)
def test_the_linear_mirror_is_the_mirror_through_positions(rig):
    motion = synthetic_walk(rig, wave="left", seconds=1.0).motion
    rig_of = _planes_of([motion])[0]
    partner = partners(motion.skeleton, rig_of.jmap)
    moving = np.zeros((motion.n_frames, motion.skeleton.n_joints), bool)
    moving[:, 0] = moving[:, 1] = True
    fast = _linear(rig_of, partner, motion.rotations, motion.translations, moving)
    slow = _through_positions(rig_of, partner, motion.rotations, motion.translations, moving)
    assert np.abs(np.abs(np.sum(fast[0] * slow[0], axis=-1)) - 1).max() < 1e-12
    np.testing.assert_allclose(fast[1], slow[1], atol=1e-9 * np.abs(slow[1]).max())


@pytest.mark.real_data
def test_stats_are_the_loaded_arrays_mean_and_std_and_survive_a_resume(clips, world, tmp_path):
    stats = world.manifest["stats"]
    assert set(stats) == set(ALL.split(",")) - {"contacts"}
    for kind, entry in stats.items():
        values = np.asarray(world.arrays[kind], dtype=np.float64)
        std = values.std(axis=0)
        assert entry["frames"] == len(values)
        np.testing.assert_allclose(entry["mean"], values.mean(axis=0), rtol=1e-5, atol=1e-5 * np.abs(values).max())
        np.testing.assert_allclose(entry["std"], np.where(std < 1e-8, 1.0, std), rtol=1e-5, atol=1e-9)
    out = tmp_path / "resumed"
    assert not run(clips, out, keep=ALL, batch_mb=4.0, max_batches=1).finished
    assert run(clips, out, keep=ALL, batch_mb=4.0).finished
    resumed = load_dataset(out).manifest["stats"]
    for kind in stats:
        np.testing.assert_allclose(resumed[kind]["mean"], stats[kind]["mean"], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(resumed[kind]["std"], stats[kind]["std"], rtol=1e-12)


@pytest.mark.real_data
@pytest.mark.parametrize("changed", [{"rotations": "quaternion"}, {"mirror": False}, {"positions": "world"}])
def test_a_resume_with_other_shaping_options_is_refused(clips, tmp_path, changed):
    first = {"keep": "rotations,positions", "rotations": "6d", "mirror": True, "positions": "root", "batch_mb": 2.0}
    out = tmp_path / "ds"
    assert not run(clips, out, max_batches=1, **first).finished
    with pytest.raises(DatasetError, match="other options"):
        run(clips, out, **{**first, **changed})
    assert run(clips, out, **first).finished


def test_a_z_up_file_gives_the_same_heading_arrays(tmp_path):
    walk = synthetic_walk("bandai", seconds=2.0).motion
    z_up = _changed(walk, quat.about("X", 90.0), 1.0)  # Y up -> Z up
    for name, motion in (("y", walk), ("z", z_up)):
        (tmp_path / name).mkdir()
        em.write_bvh(motion, tmp_path / name / "walk.bvh")
        run(tmp_path / name, tmp_path / f"{name}-world", keep="positions")
        run(tmp_path / name, tmp_path / f"{name}-ds", keep="positions,velocities,root_velocity", positions="heading")
    assert load_dataset(tmp_path / "z-world").manifest["up"] == [0.0, 0.0, 1.0]
    y, z = load_dataset(tmp_path / "y-ds"), load_dataset(tmp_path / "z-ds")
    assert y.manifest["up"] == z.manifest["up"] == [0.0, 1.0, 0.0]
    assert z.manifest["rotations_up"] == [0.0, 0.0, 1.0]  # the rotations stay in the file's world
    for kind in ("positions", "velocities", "root_velocity"):
        np.testing.assert_allclose(z.arrays[kind], y.arrays[kind], atol=2e-3)


def test_canonical_model_and_mirror_compose(tmp_path):
    folder = tmp_path / "mixed"
    folder.mkdir()
    for rig in ("bandai", "smpl", "mixamo"):
        em.write_bvh(synthetic_walk(rig, seconds=1.0).motion, folder / f"walk_{rig}.bvh")
    keep = "positions,rotations,activity,root_velocity"
    summary = run(folder, tmp_path / "ds", keep=keep, model="", canonical=True, mirror=True, positions="heading")
    assert summary.clips_ok == 6 and summary.clips_failed == 0
    ds = load_dataset(tmp_path / "ds")
    assert [c.get("mirror_of") for c in ds.clips][1::2] == ["walk_bandai", "walk_mixamo", "walk_smpl"]
    hips = find_joint_map(em.read_bvh(folder / "walk_bandai.bvh").skeleton)["hips"]
    np.testing.assert_allclose(ds.positions[:, hips, [0, 2]], 0.0, atol=1e-4)
    assert np.isfinite(ds.activity).all() and set(ds.manifest["stats"]) == set(keep.split(","))


def test_options_are_checked_and_recorded_and_load_checks_the_form(tmp_path, capsys):
    (tmp_path / "src").mkdir()
    em.write_bvh(synthetic_walk("bandai", seconds=1.0).motion, tmp_path / "src" / "walk.bvh")
    for bad in ({"rotations": "euler:XXY"}, {"rotations": "6d:ZXY"}, {"positions": "body"}, {"fps": -1}):
        with pytest.raises(ArgumentError):
            run(tmp_path / "src", tmp_path / "bad", **bad)
    args = ["preprocess", str(tmp_path / "src"), "-o", str(tmp_path / "ds"), "-q", "--keep", "rotations"]
    assert main([*args, "--rotations", "euler", "--positions", "clip", "--fps", "15", "--mirror"]) == 0
    ds = load_dataset(tmp_path / "ds")
    assert (
        ds.manifest["options"] | {"rotations": "euler:ZXY", "positions": "clip", "fps": 15.0, "mirror": True}
        == (ds.manifest["options"])
    )
    assert ds.names == ["walk", "walk@mirrored"] and ds.rotations.shape[-1] == 3
    manifest = json.loads((tmp_path / "ds" / "manifest.json").read_text())
    manifest["options"]["rotations"] = "6d"
    (tmp_path / "ds" / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(DatasetError, match="not in the form"):
        load_dataset(tmp_path / "ds")


def test_a_dask_cluster_writes_the_same_model_ready_dataset(tmp_path):
    distributed = pytest.importorskip("distributed", reason="the [distributed] extra (Dask) is not installed")
    (tmp_path / "src").mkdir()
    em.write_bvh(synthetic_walk("bandai", seconds=1.0).motion, tmp_path / "src" / "walk.bvh")
    options = {"keep": "rotations,velocities,root_velocity", "rotations": "6d", "positions": "heading", "mirror": True}
    run(tmp_path / "src", tmp_path / "single", **options)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster:
        with distributed.Client(cluster) as client:
            run(tmp_path / "src", tmp_path / "dask", cluster=client, **options)
    single, dask = load_dataset(tmp_path / "single"), load_dataset(tmp_path / "dask")
    assert single.names == dask.names and single.manifest["stats"] == dask.manifest["stats"]
    for kind in single.kinds:
        np.testing.assert_array_equal(single.arrays[kind], dask.arrays[kind])


def test_clips_of_one_frame_and_of_none_go_through_every_option(tmp_path):
    walk = synthetic_walk("bandai", seconds=1.0).motion
    (tmp_path / "src").mkdir()
    em.write_bvh(walk, tmp_path / "src" / "a.bvh")
    em.write_bvh(
        em.Motion(walk.skeleton, walk.rotations[:1], walk.translations[:1], walk.frame_time), tmp_path / "b.bvh"
    )
    text = (tmp_path / "b.bvh").read_text()
    (tmp_path / "src" / "b_one.bvh").write_text(text)
    (tmp_path / "src" / "c_none.bvh").write_text(text[: text.index("Frames:")] + "Frames: 0\nFrame Time: 0.0333333\n")
    run(tmp_path / "src", tmp_path / "ds", keep=ALL, positions="clip", mirror=True, fps=24)
    ds = load_dataset(tmp_path / "ds")
    assert [(c["name"], c["frames"]) for c in ds.clips] == [
        ("a", 25), ("a@mirrored", 25), ("b_one", 1), ("b_one@mirrored", 1), ("c_none", 0), ("c_none@mirrored", 0)
    ]  # fmt: skip
    one = ds.clip("b_one")
    for kind in ("velocities", "accelerations", "root_velocity", "angular_velocities"):
        assert np.all(one[kind] == 0), kind  # no time to change in
    assert all(np.isfinite(ds.arrays[k]).all() for k in ds.kinds if k != "contacts")


def test_stats_leave_out_clips_that_fail_after_their_kernels(tmp_path):
    """Another skeleton, a clip in other units and a mirror image's name taken: failures decided
    after the batch's sums were taken, taken out of them again."""
    walk = synthetic_walk("bandai", seconds=1.0).motion
    (tmp_path / "src").mkdir()
    em.write_bvh(walk, tmp_path / "src" / "a.bvh")
    em.write_bvh(walk.scaled(100.0), tmp_path / "src" / "b_in_other_units.bvh")
    em.write_bvh(synthetic_walk("smpl", seconds=1.0).motion, tmp_path / "src" / "c_smpl.bvh")
    em.write_bvh(walk.resample(fps=24), tmp_path / "src" / "d.bvh")
    em.write_bvh(walk.resample(fps=20), tmp_path / "src" / "a@mirrored.bvh")  # the name of a's image
    summary = run(tmp_path / "src", tmp_path / "ds", keep="positions,velocities", mirror=True)
    assert summary.clips_failed == 3 and summary.clips_ok == 4
    assert "already in the dataset" in " ".join(f["error"] for f in summary.failures)
    ds = load_dataset(tmp_path / "ds")
    for kind, entry in ds.manifest["stats"].items():
        values = np.asarray(ds.arrays[kind], dtype=np.float64)
        assert entry["frames"] == len(values)
        np.testing.assert_allclose(entry["mean"], values.mean(axis=0), atol=1e-6 * np.abs(values).max())
        std = values.std(axis=0)
        np.testing.assert_allclose(entry["std"], np.where(std < 1e-8, 1.0, std), rtol=1e-6)


@pytest.mark.real_data
def test_the_heading_kind_takes_heading_positions_back_to_the_world(clips, world, frame, tmp_path):
    run(clips, tmp_path / "ds", keep="positions,heading", positions="heading")
    ds = load_dataset(tmp_path / "ds")
    heading = ds.arrays["heading"].astype(np.float64)
    origin = np.stack([heading[:, 0], np.zeros(len(heading)), heading[:, 1]], axis=-1)
    back = from_heading(ds.positions.astype(np.float64), frame, heading[:, 2], origin)
    np.testing.assert_allclose(back, world.positions, atol=2e-3)  # the heading frames lose nothing


@pytest.mark.real_data
def test_windows_in_their_first_frame_are_the_same_from_either_stored_frame(clips, tmp_path):
    """A window's own frame found from per-frame heading positions and from per-clip ones agrees,
    and puts its first frame's hips at the origin facing +Z."""
    from expressive_mocap.dataset import WindowReader, Windows

    batches = {}
    for where in ("heading", "clip"):
        run(clips, tmp_path / where, keep="positions,velocities,heading", positions=where)
        ds = load_dataset(tmp_path / where)
        windows = Windows(ds, 40, 25)
        batches[where] = WindowReader(ds, windows, frame="window").read(np.arange(len(windows)))
    a, b = batches["heading"], batches["clip"]
    for kind in ("positions", "velocities", "heading"):
        np.testing.assert_allclose(a[kind], b[kind], atol=5e-2 if kind == "velocities" else 1e-2)
    skeleton = em.read_bvh(next(clips.glob("*.bvh"))).skeleton
    frame = HeadingFrame.of(skeleton, a["positions"][:, 0].astype(np.float64))
    first = a["positions"][:, 0].astype(np.float64)
    np.testing.assert_allclose(first[:, frame.hips, [0, 2]], 0.0, atol=1e-3)
    np.testing.assert_allclose(frame.yaw(first), 0.0, atol=1e-4)
    np.testing.assert_allclose(a["heading"][:, 0], 0.0, atol=1e-4)  # the first frame is the window's origin
    later = a["positions"][:, -1].astype(np.float64)  # later frames move away from it
    assert np.abs(later[:, frame.hips, [0, 2]]).max() > 10.0


@pytest.mark.real_data
def test_window_frames_are_refused_without_a_heading_frame(clips, tmp_path):
    from expressive_mocap.dataset import WindowReader, Windows

    run(clips, tmp_path / "world", keep="positions,heading")
    ds = load_dataset(tmp_path / "world")
    with pytest.raises(ArgumentError, match="heading frame"):
        WindowReader(ds, Windows(ds, 20), frame="window")
    run(clips, tmp_path / "nokind", keep="positions", positions="heading")
    ds = load_dataset(tmp_path / "nokind")
    with pytest.raises(ArgumentError, match="`heading` kind"):
        WindowReader(ds, Windows(ds, 20), frame="window")
