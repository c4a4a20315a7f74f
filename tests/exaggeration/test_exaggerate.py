"""Expressive features for exaggeration (METHODS.md part 1) on the synthetic intensity series
of section 3: the procedural walk 'carrying' a load k (more trunk lean, stiffer arms)."""

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body import contacts
from expressive_mocap.errors import ArgumentError, ClipError, ModelError
from expressive_mocap.exaggeration import (
    Cycle,
    ExaggerationModel,
    exaggerate,
    find_cycles,
    fit,
    lock_stance_feet,
    normalise_cycle,
    stance_foot_speed,
    subtree_weights,
    swap_test,
    to_cycle_timing,
    train,
)
from expressive_mocap.procedural import LOADED_JOINTS, loaded_walk, procedural_walk
from expressive_mocap.rotations import quat

LEVELS = [1.0, 2.0, 3.0]


@pytest.fixture(scope="module")
def clean_model():
    """One person, no performance noise: only the loaded joints change with k."""
    return train([[loaded_walk(k) for k in LEVELS]], LEVELS)


@pytest.fixture(scope="module")
def people():
    """Three 'people': the same series, each take with its own slow random wobble (0.3 degrees)."""
    return [[loaded_walk(k, wobble=0.3, seed=10 * p + i) for i, k in enumerate(LEVELS)] for p in range(3)]


@pytest.fixture(scope="module")
def model(people):
    return train(people, LEVELS)


@pytest.fixture(scope="module")
def walk():
    return loaded_walk(2.0, seconds=5.0)


def joint_rank(model):
    return [name for name, _ in sorted(model.joint_expressiveness().items(), key=lambda kv: -kv[1])]


# ----------------------------------------------------------------- cycles and time


def test_cycles_are_footstrike_to_footstrike_of_one_foot_and_follow_each_other():
    motion = procedural_walk(5.0)
    cycles = find_cycles(motion)
    assert len(cycles) >= 3
    assert len({c.foot for c in cycles}) == 1
    assert all(a.end == b.start for a, b in zip(cycles[:-1], cycles[1:]))
    strikes = contacts.footstrikes(em.foot_contacts(motion))
    ends = set(strikes[strikes[:, 1] == cycles[0].foot, 0].tolist())
    assert all(c.start in ends and c.end in ends for c in cycles)


def test_time_normalisation_and_back():
    motion = procedural_walk(3.0)
    cycle = find_cycles(motion)[0]
    part = normalise_cycle(motion, cycle, 50)
    assert part.n_frames == 50
    np.testing.assert_allclose(part.rotations[[0, -1]], motion.rotations[[cycle.start, cycle.end]], atol=1e-12)
    # A trajectory sampled on the normalised grid comes back on the cycle's own frames.
    frames = np.arange(cycle.n_frames, dtype=float)
    normalised = np.linspace(0, cycle.n_frames - 1, 50)
    np.testing.assert_allclose(to_cycle_timing(np.sin(normalised / 5), cycle.n_frames), np.sin(frames / 5), atol=2e-3)
    np.testing.assert_allclose(to_cycle_timing(normalised[:, None] * 2, cycle.n_frames)[:, 0], frames * 2, atol=1e-9)


def test_subtree_weights_sum_bone_lengths_below_a_joint():
    skeleton = procedural_walk(0.5).skeleton
    w = subtree_weights(skeleton)
    names = skeleton.names
    arm = [names.index(n) for n in ("LowerArm_L", "Hand_L")]
    assert w[names.index("UpperArm_L")] == pytest.approx(sum(np.linalg.norm(skeleton.offsets[j]) for j in arm))
    assert w[names.index("Hand_L")] == 0.0 and w[names.index("Head")] == 0.0
    assert w[0] == pytest.approx(np.linalg.norm(skeleton.offsets[1:], axis=1).sum())


# ----------------------------------------------------------------- ranking


def test_only_the_changed_joints_rank_first(clean_model, model):
    assert set(joint_rank(clean_model)[: len(LOADED_JOINTS)]) == set(LOADED_JOINTS)
    assert {clean_model.joint_of(d) for d in np.flatnonzero(clean_model.key)} <= set(LOADED_JOINTS)
    # With three wobbling people the four most expressive joints are still loaded ones: trunk and upper arms.
    assert set(joint_rank(model)[:4]) <= set(LOADED_JOINTS)
    assert model.overall.sum() == pytest.approx(1.0)
    assert model.expressiveness.shape == (3, model.n_dofs)


def test_the_swap_metric_on_the_synthetic_series_is_small(clean_model, model):
    """METHODS.md step 10 on the section 3 series. Without performance noise only the loaded joints
    differ, and the key set must be the best set of its size; with three wobbling people every
    swap (each person's key set and the union) must bring the light walk close to the heavy one,
    far closer than a random set of the same size. A key set of the wrong DOFs scores near random."""
    (clean,) = swap_test(clean_model, draws=50)
    assert clean.ratio <= clean.best + 0.01 and clean.ratio < 0.3
    assert clean.ratio_positions == pytest.approx(0.0, abs=0.15) and clean.random > 0.9
    results = swap_test(model, draws=50)
    assert [r.person for r in results] == ["0", "1", "2", "union"]
    for r in results:
        assert r.ratio < 0.3 and r.ratio_positions < 0.15, r
        assert r.ratio < r.random - 0.5 and r.ratio_positions < r.random_positions - 0.5, r


def test_predictability_is_measured_over_every_cycle():
    """Two DOFs whose performances (the means of their cycles) are equal and change with intensity:
    one steady from cycle to cycle, one scattered around the same means. Over the performances alone
    they tie; over every cycle the steady one is the more predictable. The correlations are SciPy's."""
    from scipy.stats import pearsonr

    rng = np.random.default_rng(3)
    levels, T, n = np.array([1.0, 2.0, 3.0]), 20, 6
    shape = np.sin(np.linspace(0, 2 * np.pi, T))
    spread = rng.normal(size=(3, n, T))
    spread -= spread.mean(axis=1, keepdims=True)  # zero mean per performance: the means stay equal
    cycles = np.zeros((3, n, T, 3))
    for i, k in enumerate(levels):
        cycles[i, :, :, 0] = k * shape + 0.01 * spread[i]
        cycles[i, :, :, 1] = k * shape + 5.0 * spread[i]
        cycles[i, :, :, 2] = rng.normal(size=(n, T)) * 0.1
    performances = cycles.mean(axis=1)[None]  # [P = 1, K, T, D]
    owners = np.stack([np.zeros(3 * n, int), np.repeat(np.arange(3), n)], axis=1)
    weights = np.ones(3)
    over_cycles = fit(performances, levels, weights, cycles=(cycles.reshape(3 * n, T, 3), owners), rank=2)
    over_performances = fit(performances, levels, weights, rank=2)
    E = over_performances.expressiveness[0]
    assert E[0] == pytest.approx(E[1], rel=1e-9)
    E = over_cycles.expressiveness[0]
    assert E[0] > 2 * E[1] > 0
    # The predictability behind it: SciPy's Pearson correlation over the cycles' coefficients.
    u = over_cycles.basis[:, 0]
    rho = [abs(pearsonr(cycles[..., d].reshape(3 * n, T) @ u, levels[owners[:, 1]])[0]) for d in (0, 1)]
    assert rho[0] > 0.99 and rho[1] < 0.8


def test_leave_one_out_fits_on_the_other_peoples_cycles():
    """Person p's warp uses exactly what training on the other people (every one of their cycles) gives."""
    from expressive_mocap.exaggeration import leave_one_out

    people = [
        [loaded_walk(k, seconds=3.5 + p, wobble=0.3, seed=10 * p + i) for i, k in enumerate(LEVELS)] for p in range(3)
    ]
    model = train(people, LEVELS)
    counts = np.bincount(model.cycle_performance[:, 0])
    assert len(set(counts)) == 3 and counts.min() >= 6  # several cycles a clip, a different number for each person
    warps = leave_one_out(model)
    for p in (0, 1, 2):
        others = train([people[q] for q in range(3) if q != p], LEVELS)
        change = (others.predict_coefficients(LEVELS[-1]) - others.predict_coefficients(LEVELS[0])) * others.key[
            :, None
        ]
        light, heavy = model.trajectories[p, 0], model.trajectories[p, -1]
        warped = light + others.basis @ change.T
        assert warps[p].key == int(others.key.sum())
        assert warps[p].ratio == pytest.approx(np.linalg.norm(warped - heavy) / np.linalg.norm(light - heavy), rel=1e-9)


def test_zero_length_joints_get_no_weight_and_are_reported(clean_model):
    assert set(clean_model.zero_weight_joints) == {"Head", "Hand_L", "Hand_R", "Toes_L", "Toes_R"}
    assert "weight 0" in clean_model.table()
    for name in clean_model.zero_weight_joints:
        assert clean_model.joint_expressiveness()[name] == 0.0


def test_basis_keeps_99_percent_or_a_given_rank(people):
    m = train(people[:1], LEVELS, rank=3)
    assert m.basis.shape == (50, 3)
    np.testing.assert_allclose(m.basis.T @ m.basis, np.eye(3), atol=1e-10)
    assert train(people[:1], LEVELS).energy >= 0.99


def test_euler_channels_rank_the_same_joints():
    m = train([[loaded_walk(k) for k in LEVELS]], LEVELS, representation="euler")
    assert m.dof_names[6] == "Spine.Zrot"
    assert set(joint_rank(m)[:2]) == {"Spine", "Chest"}


# ----------------------------------------------------------------- exaggeration


def test_exaggerating_to_the_current_intensity_is_the_identity(model, walk):
    out, report = exaggerate(model, walk, 2.0, current=2.0)
    np.testing.assert_array_equal(out.rotations, walk.rotations)
    np.testing.assert_allclose(out.translations, walk.translations, atol=1e-9)
    assert report.clamped == {} and max(report.largest_change.values()) < 1e-9


def test_diminish_then_exaggerate_returns_the_input(clean_model, walk):
    """Tolerance: 1e-6 degrees and 1e-6 cm (log/exp round trips; no clamping in range)."""
    cycles = find_cycles(walk)
    down, report = exaggerate(clean_model, walk, 1.5, current=2.0, cycles=cycles, lock_feet=False)
    assert report.clamped == {}
    assert max(report.largest_change.values()) > 1.0
    back, _ = exaggerate(clean_model, down, 2.0, current=1.5, cycles=cycles, lock_feet=False)
    assert np.degrees(quat.angle(quat.mul(quat.conjugate(back.rotations), walk.rotations))).max() < 1e-6
    assert np.abs(back.positions() - walk.positions()).max() < 1e-6


def test_intensity_is_estimated_from_the_mapping(clean_model):
    for k in (1.5, 2.0, 2.5):
        _, report = exaggerate(clean_model, loaded_walk(k, 5.0), k + 1)
        assert report.k0_estimated and report.k0 == pytest.approx(k, abs=0.1)


def lean(motion, walk, frames=slice(None)):
    """Extra forward lean of the spine (degrees, mean over the clip) of ``motion`` over ``walk``:
    loaded_walk leans by turning the spine -4 degrees per unit of k about its local Z."""
    j = motion.skeleton.names.index("Spine")
    change = quat.mul(quat.conjugate(walk.rotations[frames, j]), motion.rotations[frames, j])
    return -float(np.degrees(quat.log(change)[:, 2]).mean())


def test_exaggeration_follows_the_training_series_and_extrapolates(clean_model, walk):
    cycles = find_cycles(walk)
    inside = slice(cycles[0].start + 5, cycles[-1].end - 5)  # the lead-in and -out keep their lean
    # A margin wide enough for k = 0.5 and 3.5 (the default 0.1 x the trained range would clamp them).
    leans = [
        lean(exaggerate(clean_model, walk, k, current=2.0, margin=0.5)[0], walk, inside)
        for k in (0.5, 1.0, 2.0, 3.0, 3.5)
    ]
    assert np.all(np.diff(leans) > 0)
    # As much as the real k = 3 walk leans more (4 degrees).
    assert leans[3] == pytest.approx(lean(loaded_walk(3.0, 5.0), walk, inside), abs=0.3)
    assert leans[4] > leans[3] + 1.0


def test_every_cycle_is_edited_and_there_is_no_seam(clean_model, walk):
    out, report = exaggerate(clean_model, walk, 3.5, current=2.0)
    cycles = report.cycles
    assert len(cycles) >= 3 and cycles[0].start > 0
    # Frames far before the first footstrike keep their values; every cycle changes.
    np.testing.assert_allclose(out.rotations[: cycles[0].start - 6], walk.rotations[: cycles[0].start - 6], atol=1e-12)
    j = walk.skeleton.names.index("UpperArm_R")
    for c in cycles:
        assert np.abs(out.rotations[c.start : c.end, j] - walk.rotations[c.start : c.end, j]).max() > 1e-3
    # No seam: the frame-to-frame rotation change stays close to the input's everywhere.
    step = lambda m: np.degrees(quat.angle(quat.mul(quat.conjugate(m.rotations[:-1]), m.rotations[1:])))  # noqa: E731
    assert (step(out) - step(walk)).max() < 1.5


def test_large_changes_are_clamped_and_reported(clean_model, walk):
    out, report = exaggerate(clean_model, walk, 30.0, current=2.0)
    assert "Spine.rz" in report.clamped
    assert "clamped" in report.text()
    free, _ = exaggerate(clean_model, walk, 30.0, current=2.0, margin=100.0)
    assert lean(free, walk) > lean(out, walk) + 5


def test_the_clamping_range_is_measured_as_the_edit_measures(walk):
    """Two people whose left upper arms differ by a constant 20 degrees: the people's mean lies between
    them. Diminishing the second person's walk to an intensity they performed in training must stay
    inside the training range even with no margin; a range measured from each person's own mean
    would be 10 degrees off for both and clamp the arm swing (by 4 degrees here)."""

    def turned(motion):
        rotations = motion.rotations.copy()
        j = motion.skeleton.names.index("UpperArm_L")
        rotations[:, j] = quat.mul(rotations[:, j], quat.about("Y", 20.0))
        return em.Motion(motion.skeleton, rotations, motion.translations, motion.frame_time)

    model = train([[loaded_walk(k) for k in LEVELS], [turned(loaded_walk(k)) for k in LEVELS]], LEVELS)
    _, report = exaggerate(model, turned(walk), 1.0, current=2.0, margin=0.0)
    assert all(np.degrees(excess) < 0.5 for _, excess in report.clamped.values()), report.clamped


def test_foot_locking_pins_the_stance_foot(walk):
    """An edit that swings both thighs 12 degrees (the feet skate), locked: in contact the ankles
    and toes are back where the input has them; beyond the 3-frame blend the edit is untouched."""
    roles = em.Body.of(walk.skeleton).roles
    contacts = em.foot_contacts(walk)
    rotations = walk.rotations.copy()
    for j in roles.upper_legs:
        rotations[:, j] = quat.mul(quat.about("X", 12.0), rotations[:, j])
    edited = em.Motion(walk.skeleton, rotations, walk.translations, walk.frame_time)
    locked, correction, residual, lowered = lock_stance_feet(walk, edited, contacts, roles, blend_frames=3)
    assert correction > 5.0 and residual < 1e-6 and lowered == 0.0  # the thighs' swing keeps the feet within reach
    assert stance_foot_speed(edited, contacts) > 2 * stance_foot_speed(walk, contacts)
    assert stance_foot_speed(locked, contacts) == pytest.approx(stance_foot_speed(walk, contacts), abs=1e-6)
    for s in (0, 1):
        for joint in (roles.feet[s], roles.toes[s]):
            gap = np.linalg.norm(
                locked.positions()[contacts[:, s], joint] - walk.positions()[contacts[:, s], joint], axis=1
            )
            assert gap.max() < 1e-6
    for s in (0, 1):
        far = ~np.convolve(contacts[:, s], np.ones(7), mode="same").astype(bool)  # > 3 frames from the foot's contacts
        assert far.sum() > 10
        leg = [roles.upper_legs[s], walk.skeleton.parents[roles.feet[s]], roles.feet[s]]
        np.testing.assert_array_equal(locked.rotations[far][:, leg], edited.rotations[far][:, leg])
    # Eased, not popped: the thighs turn no faster than in the edit plus a little.
    step = lambda m: np.degrees(quat.angle(quat.mul(quat.conjugate(m.rotations[:-1]), m.rotations[1:])))  # noqa: E731
    legs = [*roles.upper_legs, *(walk.skeleton.parents[f] for f in roles.feet)]
    assert step(locked)[:, legs].max() < step(edited)[:, legs].max() + 4.0


def real_walk(data, name):
    return em.read_bvh(data / f"dataset-2_walk_{name}.bvh")


def real_walk_people(data, takes):
    """Dataset-2's walks, take ``p`` of each style as person ``p``, styles in intensity order."""
    return [[real_walk(data, f"{style}_{p:03d}") for style in ("exhausted", "normal", "active")] for p in takes]


def test_foot_locking_on_a_real_walk(bandai2_dir):
    """Two takes of dataset-2's walks as people; a third take's normal walk exaggerated far beyond
    'active': without locking its stance feet slide about 3x as far a step as in the input.
    Compared per step, not per second: the edit also quickens the walk (x1.19 here), and a walk
    played quicker rolls its stance feet as far in less time."""
    model = train(real_walk_people(bandai2_dir, (1, 2)), LEVELS)
    walk = real_walk(bandai2_dir, "normal_012")
    _, locked = exaggerate(model, walk, 4.0)
    _, loose = exaggerate(model, walk, 4.0, lock_feet=False)
    assert locked.timing is not None and loose.timing is not None and locked.timing.duration < 0.9
    per_step = locked.timing.duration  # seconds of output per second of input
    assert loose.stance_speed_output * per_step > 1.5 * loose.stance_speed_input
    assert locked.stance_speed_output * per_step <= 1.2 * locked.stance_speed_input


def test_the_issue_targets_on_real_walks(bandai2_dir):
    """The paper's validation on dataset-2's walks, takes 1-8 as people (experiments/EXAGGERATION.md has
    the full tables): the issue's bars for the swap test and the leave-one-person-out warp."""
    from expressive_mocap.exaggeration import leave_one_out

    model = train(real_walk_people(bandai2_dir, range(1, 9)), LEVELS)
    *per_person, union = swap_test(model, draws=100)
    for r in per_person:
        assert r.ratio <= 0.40 and r.ratio <= r.random - 0.3, r
    assert union.ratio <= 0.30 and union.ratio_positions <= 0.10, union
    assert np.mean([w.ratio for w in leave_one_out(model)]) <= 0.45


def test_the_cycles_start_at_the_footstrikes_of_the_trained_foot(walk):
    right = train([[loaded_walk(k) for k in LEVELS]], LEVELS, foot=1)
    assert right.settings.foot == 1
    _, report = exaggerate(right, walk, 3.0, current=2.0)
    assert {c.foot for c in report.cycles} == {1} and report.cycles == find_cycles(walk, foot=1)


def test_a_clip_with_no_steps_is_edited_as_a_whole(clean_model):
    standing = loaded_walk(2.0, 1.0)[:10]
    out, report = exaggerate(clean_model, standing, 3.0, current=2.0)
    assert report.cycles == [Cycle(0, 9)]
    assert out.n_frames == 10


# ----------------------------------------------------------------- files


def test_save_load_round_trip(model, walk, tmp_path):
    path = tmp_path / "m.npz"
    model.save(path)
    again = ExaggerationModel.load(path)
    for name in ExaggerationModel._ARRAYS:
        np.testing.assert_array_equal(getattr(again, name), getattr(model, name))
    assert again.dof_names == model.dof_names and again.settings == model.settings
    a, _ = exaggerate(model, walk, 3.0)
    b, _ = exaggerate(again, walk, 3.0)
    # Equal arrays, not equal layouts: the trained basis and mappings are strided views, the
    # loaded ones contiguous (and elsewhere in memory), so einsum and BLAS may sum in another
    # order: fresh-clone CI runs differed by 6e-14 after the IK, and by 1.2e-12 with NumPy 2's
    # BLAS through the intensity estimate's least squares. A wrong array, key set or setting would
    # move rotations by far more than 1e-9.
    np.testing.assert_allclose(a.rotations, b.rotations, rtol=0, atol=1e-9)


def test_damaged_model_files_give_clear_errors(model, tmp_path):
    with pytest.raises(ModelError, match="not a readable"):
        ExaggerationModel.load(b"not a zip")
    with pytest.raises(ModelError, match="cannot read"):
        ExaggerationModel.load(tmp_path / "missing.npz")
    import io

    with np.load(io.BytesIO(model.to_bytes())) as archive:
        arrays = {k: archive[k] for k in archive.files}
    arrays["basis"] = arrays["basis"][:, :1]
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    with pytest.raises(ModelError, match="expected finite numbers of shape"):
        ExaggerationModel.load(buffer.getvalue())
    del arrays["mappings"]
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    with pytest.raises(ModelError, match="lacks"):
        ExaggerationModel.load(buffer.getvalue())


# ----------------------------------------------------------------- bad inputs


def test_bad_inputs_give_clear_errors(clean_model, walk):
    walks = [loaded_walk(k, 2.0) for k in LEVELS]
    with pytest.raises(ArgumentError, match="increasing"):
        train([walks], [3, 2, 1])
    with pytest.raises(ArgumentError, match="one clip per intensity"):
        train([walks[:2]], LEVELS)
    with pytest.raises(ArgumentError, match="degree"):
        train([walks], LEVELS, degree=3)
    with pytest.raises(ArgumentError, match="representation"):
        train([walks], LEVELS, representation="matrix")
    with pytest.raises(ArgumentError, match="cycle must be"):
        train([walks], LEVELS, cycle="best")
    with pytest.raises(ArgumentError, match="foot must be"):
        train([walks], LEVELS, foot=2)
    with pytest.raises(ClipError, match="no gait cycle"):
        train([[w[:20] for w in walks]], LEVELS)
    with pytest.raises(ModelError, match="skeleton"):
        exaggerate(clean_model, _renamed(walk), 3.0)
    with pytest.raises(ArgumentError, match="finite"):
        exaggerate(clean_model, walk, float("nan"))
    with pytest.raises(ArgumentError, match="reference"):
        exaggerate(clean_model, walk, 3.0, reference="mine")


def _renamed(motion):
    s = motion.skeleton
    names = ("Root",) + s.names[1:]
    return em.Motion(
        em.Skeleton(names, s.parents, s.offsets, s.channels, s.end_sites),
        motion.rotations,
        motion.translations,
        motion.frame_time,
    )


# ----------------------------------------------------------------- commands


def test_rank_exaggerate_validate_commands(tmp_path, capsys):
    from expressive_mocap.cli import main

    files = {}
    for p in range(2):
        for i, k in enumerate(LEVELS):
            files[p, k] = tmp_path / f"p{p}_k{k:g}.bvh"
            em.write_bvh(loaded_walk(k, wobble=0.3, seed=10 * p + i), files[p, k])
    levels = [a for k in LEVELS for a in ("--level", f"{k:g}", str(files[0, k]), str(files[1, k]))]
    plot, saved = tmp_path / "rank.png", tmp_path / "model.npz"
    assert main(["rank", *levels, "-o", str(plot), "-o", str(saved)]) == 0
    out = capsys.readouterr().out
    assert "key DOFs" in out and "person 1:" in out and plot.stat().st_size > 1000
    assert main(["rank", *levels, "--cycle", "0"]) == 0 and "key DOFs" in capsys.readouterr().out  # a cycle by index
    walk = tmp_path / "walk.bvh"
    em.write_bvh(loaded_walk(2.0, 4.0), walk)
    result = tmp_path / "out.bvh"
    assert (
        main(["exaggerate", "--model", str(saved), "--input", str(walk), "--from", "2", "--to", "3", "-o", str(result)])
        == 0
    )
    out = capsys.readouterr().out
    assert "largest change per joint" in out and em.read_bvh(result).n_frames == em.read_bvh(walk).n_frames
    assert main(["validate", "--model", str(saved), "--draws", "20"]) == 0
    out = capsys.readouterr().out
    assert "union" in out and "leave-one-person-out" in out and "rank agreement" in out


def test_commands_fail_in_one_line(tmp_path, capsys):
    from expressive_mocap.cli import main

    walk = tmp_path / "w.bvh"
    em.write_bvh(loaded_walk(1.0, 2.0), walk)
    assert main(["rank", "--level", "1", str(walk)]) == 1
    assert "at least two --level" in capsys.readouterr().err
    assert main(["rank", "--level", "1", str(walk), "--level", "2", str(walk), str(walk)]) == 1
    assert "same number of files" in capsys.readouterr().err
    assert main(["rank", "--level", "1", str(walk), "--level", "2", str(walk), "-o", "x.txt"]) == 1
    assert ".png" in capsys.readouterr().err
    assert main(["rank", "--level", "1", str(walk), "--level", "2", str(walk), "--cycle", "best"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cycle must be one of all, middle" in err
    assert (
        main(
            [
                "exaggerate",
                "--model",
                str(tmp_path / "none.npz"),
                "--input",
                str(walk),
                "--to",
                "2",
                "-o",
                str(tmp_path / "o.bvh"),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot read" in err


def test_rank_names_the_clip_it_cannot_use_and_the_option_to_use(tmp_path, mixed_path, capsys):
    from expressive_mocap.cli import main

    files = {}
    for p in range(2):
        for i, k in enumerate(LEVELS):
            files[p, k] = tmp_path / f"p{p}_k{k:g}.bvh"
            em.write_bvh(loaded_walk(k, wobble=0.3, seed=10 * p + i), files[p, k])
    short = tmp_path / "short.bvh"
    em.write_bvh(em.read_bvh(files[1, LEVELS[1]])[:31], short)  # 31 frames: no foot strikes twice
    levels = [
        a
        for k in LEVELS
        for a in ("--level", f"{k:g}", str(files[0, k]), str(short if k == LEVELS[1] else files[1, k]))
    ]
    assert main(["rank", *levels]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(
        f"expressive-mocap: error: {short}: no gait cycle found in its 31 frames"
    )
    assert "--cycle whole" in err
    levels = [
        a
        for k in LEVELS
        for a in ("--level", f"{k:g}", str(files[0, k]), str(mixed_path if k == LEVELS[2] else files[1, k]))
    ]
    assert main(["rank", *levels]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"expressive-mocap: error: {mixed_path}: another skeleton") and err.count("\n") == 1
    assert main(["rank", *levels[:-4], "-o", str(tmp_path / "m.npz")]) == 0  # two levels, both people fine
    capsys.readouterr()
    assert (
        main(
            [
                "exaggerate",
                "--model",
                str(tmp_path / "m.npz"),
                "--input",
                str(mixed_path),
                "--to",
                "3",
                "-o",
                str(tmp_path / "x.bvh"),
            ]
        )
        == 1
    )
    err = capsys.readouterr().err
    assert (
        err.startswith(f"expressive-mocap: error: {mixed_path}: the model was trained on")
        and "`expressive-mocap rank" in err
    )


def test_foot_locking_lowers_the_hips_where_a_leg_cannot_reach(walk):
    """An edit that raises the hips 5% of the actor's height: the stance legs cannot reach the
    input's ankles, so the hips come down just enough, eased; the feet stay planted."""
    body = em.Body.of(walk.skeleton)
    roles, height = body.roles, body.actor_height
    contacts = em.foot_contacts(walk)
    translations = walk.translations.copy()
    translations[:, roles.hips, 1] += 0.05 * height  # the hips' parent is the identity in the demo walk
    edited = em.Motion(walk.skeleton, walk.rotations, translations, walk.frame_time)
    locked, _, residual, lowered = lock_stance_feet(walk, edited, contacts, roles, blend_frames=3)
    assert residual < 1e-3 * height and 0.0 < lowered <= 0.05 * height + 1e-9
    for s in (0, 1):
        gap = np.abs(
            locked.positions()[contacts[:, s], roles.feet[s], 1] - walk.positions()[contacts[:, s], roles.feet[s], 1]
        )
        assert gap.max() < 1e-3 * height  # before: the stance feet hung up to 5% of the height above the floor
    hips = locked.positions()[:, roles.hips]
    assert np.abs(np.diff(hips[:, 1])).max() < np.abs(np.diff(walk.positions()[:, roles.hips, 1])).max() + 0.01 * height
