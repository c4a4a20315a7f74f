"""Foot contacts, air time, contact intervals and the footsteps command: cases by hand, the
filters' edge rules, Rust/NumPy parity, real Bandai-Namco walks and the demo walk."""

import subprocess
import sys

import numpy as np
import pytest

import expressive_mocap as em
from conftest import stick_walker
from expressive_mocap import ops, reference
from expressive_mocap.body import contacts
from expressive_mocap.body.contacts import (
    ContactInterval,
    air_time,
    cadence,
    contact_intervals,
    foot_contacts,
    footstrikes,
)
from expressive_mocap.cli import main
from expressive_mocap.decoupling import features
from expressive_mocap.procedural import procedural_walk

STYLES = ["normal", "active", "exhausted", "elderly", "feminine", "masculine", "youthful"]


def resting_walker(frames=50, rest=range(20, 30)):
    """Hips walking along +Z; the left ankle slides on the floor at 150 cm/s (fast: no contact)
    except on the frames ``rest``, where its velocity is 0; the right foot stays 30 cm up."""
    t = np.arange(frames)
    moving = np.ones(frames)
    moving[list(rest)] = 0.0
    z = 5.0 * np.cumsum(np.r_[0.0, moving[1:]])  # backward differences: velocity 0 on `rest`
    left = np.stack([np.full(frames, 10.0), np.zeros(frames), z], axis=1)
    right = np.stack([np.full(frames, -10.0), np.full(frames, 30.0), 5.0 * t], axis=1)
    hips = np.stack([np.zeros(frames), np.full(frames, 90.0), 5.0 * t], axis=1)
    return stick_walker(hips, left, right)


def test_a_foot_that_stops_for_ten_frames_is_one_contact(backend):
    walker = resting_walker()
    contacts = foot_contacts(walker, floor=0.0)
    assert contact_intervals(contacts, walker.frame_time) == [[ContactInterval(20, 29, pytest.approx(10 / 30))], []]
    # The causal detector sees the same contact once it has lasted 0.1 s (3 frames): 2 frames late.
    # Frame 0 has no past, so its speed counts as 0: a foot on the floor starts in contact and
    # leaves it once it has moved for 3 frames.
    causal = foot_contacts(walker, floor=0.0, causal=True)
    expected = [ContactInterval(0, 2, pytest.approx(0.1)), ContactInterval(22, 31, pytest.approx(10 / 30))]
    assert contact_intervals(causal[:, 0], walker.frame_time) == expected


def test_a_lifted_foot_is_not_in_contact_and_thresholds_scale_with_height(backend):
    walker = resting_walker()
    # 30 cm up is 0.21 actor heights: in contact only with a higher threshold.
    assert not foot_contacts(walker, floor=0.0)[:, 1].any()
    assert foot_contacts(walker, floor=0.0, height_threshold=0.25, speed_threshold=2.0)[:, 1].all()
    # The same walk in metres gives the same contacts (thresholds are relative to the actor).
    np.testing.assert_array_equal(foot_contacts(walker.scaled(0.01), floor=0.0), foot_contacts(walker, floor=0.0))


def _heights(text):
    """Feet [F, 1, 1, 3] at height 0 ('#': touching) or 10 ('.'); speed never matters below."""
    y = np.array([0.0 if c == "#" else 10.0 for c in text])
    feet = np.zeros((len(text), 1, 1, 3))
    feet[:, 0, 0, 1] = y
    return feet


def _flags(text):
    return np.array([c == "#" for c in text])


@pytest.mark.parametrize(
    "raw, offline, causal",
    [
        # a one-frame flicker either way is absorbed (offline) or never held (causal)
        ("##########.#########", "####################", "####################"),
        ("..........#.........", "....................", "...................."),
        # two frames too; three frames (0.1 s at 30 fps) are a real run
        ("#######..###########", "####################", "####################"),
        ("#######...##########", "#######...##########", "#########...########"),
        # runs at the clip's ends are kept offline (the clip cut them, they may be longer)
        ("#.......", "#.......", "###....."),
        # shortest run first (earliest among equals): the lone '#', then the lone '.' between contacts
        ("###...#.....##.#####", "###.........########", "#####............###"),
    ],
)
def test_temporal_filters(backend, raw, offline, causal):
    def run(is_causal):
        return ops.foot_contacts(_heights(raw), 1 / 30, 0.0, 5.0, 1e9, 3, is_causal)[:, 0]

    np.testing.assert_array_equal(run(False), _flags(offline), err_msg="offline")
    np.testing.assert_array_equal(run(True), _flags(causal), err_msg="causal")


def test_either_point_of_a_foot_counts(backend):
    feet = np.zeros((6, 1, 2, 3))
    feet[:, 0, 0, 1] = [0, 0, 0, 10, 10, 10]  # ankle down, then up
    feet[:, 0, 1, 1] = [10, 10, 10, 10, 0, 0]  # toe up, then down (frame 4 moves: too fast)
    contacts = ops.foot_contacts(feet, 1.0, 0.0, 5.0, 5.0, 1, False)[:, 0]
    np.testing.assert_array_equal(contacts, [True, True, True, False, False, True])


def test_air_time_counts_seconds_since_the_foot_left(backend):
    contacts = np.array([[0, 1], [1, 1], [0, 1], [0, 0], [1, 0]], dtype=bool)
    np.testing.assert_allclose(air_time(contacts, 0.5), [[0.5, 0], [0, 0], [0.5, 0], [1.0, 0.5], [0, 1.0]])


def test_intervals_strikes_and_cadence_by_hand():
    contacts = np.zeros((30, 2), dtype=bool)
    contacts[0:5, 0] = contacts[20:25, 0] = contacts[10:15, 1] = contacts[29, 1] = True
    assert contact_intervals(contacts[:, 0], 0.1) == [
        ContactInterval(0, 4, pytest.approx(0.5)),
        ContactInterval(20, 24, pytest.approx(0.5)),
    ]
    assert contact_intervals(contacts, 0.1)[1][-1] == ContactInterval(29, 29, pytest.approx(0.1))
    # The contact at frame 0 began before the clip: not a footstrike.
    assert footstrikes(contacts).tolist() == [[10, 1], [20, 0], [29, 1]]
    assert cadence(contacts, 0.1) == pytest.approx(2 / 1.9)
    assert np.isnan(cadence(contacts[:15], 0.1))


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
@pytest.mark.parametrize("causal", [False, True])
def test_rust_matches_numpy_twin(causal):
    from expressive_mocap import _core

    rng = np.random.default_rng(3)
    # Noisy feet near both thresholds: many flickers for the filters to work on.
    feet = np.cumsum(rng.normal(scale=1.0, size=(2000, 2, 2, 3)), axis=0) * [1, 0, 1]
    feet[..., 1] = rng.uniform(0, 10, size=feet.shape[:3])
    args = (1 / 30, 1.0, 5.0, 30.0)
    for min_frames in (1, 3, 7):
        rust = _core.foot_contacts(feet, *args, min_frames, causal)
        numpy = reference.foot_contacts(feet, *args, min_frames, causal)
        assert rust.dtype == numpy.dtype == bool and rust.shape == (2000, 2)
        np.testing.assert_array_equal(rust, numpy)
        np.testing.assert_array_equal(_core.air_time(rust, 1 / 30), reference.air_time(numpy, 1 / 30))


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda m: foot_contacts(m, height_threshold=-1), "height_threshold"),
        (lambda m: foot_contacts(m, speed_threshold=float("nan")), "speed_threshold"),
        (lambda m: foot_contacts(m, min_duration=0), "min_duration"),
        (lambda m: foot_contacts(m, floor=float("inf")), "floor"),
        (lambda m: foot_contacts(m.positions()), "motion"),
        (lambda m: air_time(np.zeros(3, dtype=bool), 0.1), "contacts"),
        (lambda m: air_time(np.zeros((3, 2), dtype=bool), 0), "frame_time"),
        (lambda m: contact_intervals(np.zeros((2, 2, 2)), 0.1), "contacts"),
        (lambda m: footstrikes(np.zeros(4)), "contacts"),
    ],
)
def test_argument_errors_name_the_argument(backend, call, name):
    with pytest.raises(em.MocapError, match=f"`{name}`"):
        call(resting_walker(frames=10, rest=range(3, 6)))


@pytest.mark.parametrize("name, value", [("feet", np.zeros((4, 2, 2, 2))), ("frame_time", -1.0), ("min_frames", 0)])
def test_kernel_errors_name_the_argument(backend, name, value):
    arguments = dict(
        feet=np.zeros((4, 2, 2, 3)),
        frame_time=0.1,
        floor=0.0,
        height_threshold=1.0,
        speed_threshold=1.0,
        min_frames=3,
        causal=False,
    )
    arguments[name] = value
    with pytest.raises(em.errors.ArgumentError, match=f"`{name}`"):
        ops.foot_contacts(*arguments.values())


def test_demo_walk_has_contacts_on_both_feet(backend):
    walk = procedural_walk(seconds=4.0)
    for causal in (False, True):
        intervals = contact_intervals(foot_contacts(walk, causal=causal), walk.frame_time)
        assert all(len(foot) >= 3 for foot in intervals), intervals


@pytest.mark.real_data
@pytest.mark.parametrize("style", STYLES)
def test_real_walks_step_left_right_at_a_walking_cadence(backend, bandai2_dir, style):
    walk = em.read_bvh(bandai2_dir / f"dataset-2_walk_{style}_001.bvh")
    for causal in (False, True):
        contacts = foot_contacts(walk, causal=causal)
        strikes = footstrikes(contacts)
        rate = cadence(contacts, walk.frame_time)
        message = (
            f"{style} walk ({'causal' if causal else 'offline'}): {rate:.2f} steps/s, feet {strikes[:, 1].tolist()}"
        )
        assert len(strikes) >= 6, message
        assert (np.diff(strikes[:, 1]) != 0).all(), message  # left, right, left, ...
        assert 1.2 < rate < 2.6, message  # people walk at 1.5-2.3 steps a second
        print(message)


@pytest.mark.real_data
def test_real_walk_parity_through_the_public_api(bandai2_dir):
    if not em.rust_available():
        pytest.skip("the Rust extension is not built")
    walk = em.read_bvh(bandai2_dir / "dataset-2_walk-turn-left_normal_001.bvh")
    results = []
    for name in ("rust", "numpy"):
        with em.use_backend(name):
            results.append([foot_contacts(walk), foot_contacts(walk, causal=True)])
    for rust, numpy in zip(*results):
        np.testing.assert_array_equal(rust, numpy)


def test_footsteps_command_prints_intervals_and_writes_a_plot(tmp_path, capsys):
    path = tmp_path / "walk.bvh"
    em.write_bvh(resting_walker(), path)
    plot = tmp_path / "contacts.png"
    assert main(["footsteps", str(path), "--plot", str(plot), "--floor", "0"]) == 0
    out = capsys.readouterr().out
    assert "left foot (LeftFoot, LeftToeBase): 1 contact" in out
    assert "frames    20-29       0.667-1.000 s  (0.333 s)" in out
    assert "right foot (RightFoot, RightToeBase): 0 contacts" in out
    assert "summary: 1 steps (1 left, 0 right), cadence: too few steps" in out
    assert plot.read_bytes()[:4] == b"\x89PNG"
    assert main(["footsteps", str(path), "--causal", "--height-threshold", "0.25", "--speed-threshold", "2"]) == 0
    assert "right foot (RightFoot, RightToeBase): 1 contact" in capsys.readouterr().out


@pytest.mark.parametrize(
    "args, words",
    [
        (["footsteps", "missing.bvh"], "cannot read"),
        (["footsteps", "WALK", "--height-threshold", "0"], "must be positive"),
        (["footsteps", "WALK", "--plot", "no/such/folder/p.png"], "does not exist"),
        (["footsteps", "NOROLES"], "cannot tell which joint"),
    ],
)
def test_footsteps_command_errors_are_one_line(tmp_path, mixed_path, args, words):
    em.write_bvh(resting_walker(), tmp_path / "walk.bvh")
    args = [{"WALK": "walk.bvh", "NOROLES": str(mixed_path)}.get(a, a) for a in args]
    result = subprocess.run(
        [sys.executable, "-m", "expressive_mocap.cli", *args], capture_output=True, text=True, cwd=tmp_path
    )
    assert result.returncode != 0
    assert "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert words in result.stderr


def test_footsteps_help_reads_well(capsys):
    with pytest.raises(SystemExit):
        main(["footsteps", "--help"])
    out = capsys.readouterr().out
    for words in ["Lee et al. 2002", "--plot OUT.png", "--causal", "x actor height", "default: 0.05"]:
        assert words in out


def test_contacts_and_features_module_exports():
    assert set(contacts.__all__) >= {"foot_contacts", "air_time", "contact_intervals"}
    assert set(features.__all__) >= {"dynamic_features", "FEATURE_NAMES"}
