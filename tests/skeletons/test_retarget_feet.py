"""Feet on the floor after a retarget: a flat stance foot stays flat on the target (each foot
carried as a change from its rig's flat-footed reference pose, not bone by bone), and the stance
feet stand on the target's own floor (however high each rig sets its ankle above its sole).

Measured as a viewer would, with the source's contacts: the stance ankle and toe heights and the
foot's pitch (ankle to toe joint against the floor) of the retarget against those of a walk of
the target rig itself. Before, on the Bandai-Namco body: toes 13-15 cm up (its own walk: 4.6),
ankles 16-18 cm (12.5), feet pitched 15-20 degrees down (43)."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.conventions import read_conventions, upright
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.motion import Motion
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.canonical import onto_canonical
from expressive_mocap.skeletons.retargeting import retarget


def stance(motion: Motion, contacts: np.ndarray | None = None) -> np.ndarray:
    """(ankle height, toe joint height, foot pitch in degrees) averaged over both feet's contacts
    (``contacts``: the motion's own by default), in its canonical axes (Y up, file units)."""
    jmap = find_joint_map(motion.skeleton)
    from expressive_mocap.rotations import quat

    points = quat.rotate(read_conventions(motion, jmap).rotation(), motion.positions())
    contacts = foot_contacts(motion) if contacts is None else contacts
    out = []
    for s, side in enumerate(("left", "right")):
        ankle, toe = points[:, jmap[f"{side}_foot"]], points[:, jmap[f"{side}_toes"]]
        line = toe - ankle
        pitch = np.degrees(np.arctan2(line[:, 1], np.linalg.norm(line[:, [0, 2]], axis=1)))
        on = contacts[:, s]
        out.append((ankle[on, 1].mean(), toe[on, 1].mean(), pitch[on].mean()))
    return np.mean(out, axis=0)


@pytest.mark.parametrize("rig", ["cmu", "mixamo", "game", "smpl", "lafan"])
def test_a_walk_of_another_rig_stands_on_the_bandai_body_as_its_own_walk_does(rig):
    """The synthetic rigs carry the demo's Bandai walk at their own rates, units and axes (the CMU
    one's stance ankle is 5 cm above its floor, Bandai's 12.9); carried back onto the Bandai body,
    the stance feet must be the demo walk's own. (Their legs share the Bandai geometry, so this
    checks the round trip; the real walks below have feet of their own.)"""
    own = synthetic_walk("bandai", seconds=4.0).motion
    source = synthetic_walk(rig, seconds=4.0).motion
    out = retarget(source, own, plant_feet=False)
    contacts = foot_contacts(upright(source))  # the source's, read Y up (the game rig is Z up)
    got = stance(out, contacts)
    want = stance(own)
    assert abs(got[0] - want[0]) < 1.0 and abs(got[1] - want[1]) < 1.0, (rig, got, want)  # cm
    assert abs(got[2] - want[2]) < 5.0, (rig, got, want)  # degrees


@pytest.mark.real_data
def test_real_walks_of_other_rigs_stand_on_the_canonical_body_as_a_bandai_walk_does(other_dir, bandai2_dir):
    """The CMU and 21-joint walks on the canonical body: stance ankle and toe within 1 cm of a
    dataset-2 walk's, foot pitch within 5 degrees."""
    want = stance(em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh"))
    for name in ("m21_walk", "m21_female-walk", "cmu_scaled_131_03"):
        source = em.read_bvh(other_dir / f"{name}.bvh")
        out, _ = onto_canonical(source, plant_feet=False)
        got = stance(out, foot_contacts(source))
        assert abs(got[0] - want[0]) < 1.0 and abs(got[1] - want[1]) < 1.0, (name, got, want)
        assert abs(got[2] - want[2]) < 5.0, (name, got, want)


def stance_speed(motion: Motion, contacts: np.ndarray) -> float:
    """The stance ankles' and toe joints' horizontal speed over pairs of frames in ``contacts``,
    in actor heights a second (so that rigs of any unit compare)."""
    from expressive_mocap.rotations import quat

    jmap = find_joint_map(motion.skeleton)
    conventions = read_conventions(motion, jmap)
    points = quat.rotate(conventions.rotation(), motion.positions())
    steps = []
    for s, side in enumerate(("left", "right")):
        both = contacts[1:, s] & contacts[:-1, s]
        for part in ("foot", "toes"):
            moved = np.diff(points[:, jmap[f"{side}_{part}"]][:, [0, 2]], axis=0)
            steps.append(np.linalg.norm(moved, axis=1)[both])
    return float(np.concatenate(steps).mean() * motion.fps / conventions.height)


@pytest.mark.real_data
def test_real_walks_keep_their_stance_feet_on_the_canonical_body(other_dir):
    """Stance feet (the source's contacts) at most 1.1x the source's speed once planted. A walk on
    the balls of its feet (dme_comp_3d_2: the heel up, the foot turning about the toe) slid its
    toes at 1.13x while its ankles followed the source's: the toe is now the pivot where the
    source's toe is the still one."""
    for name in ("m21_walk", "m21_female-walk", "cmu_scaled_131_03", "cmu_01_01", "dme_comp_3d_2"):
        source = em.read_bvh(other_dir / f"{name}.bvh")
        contacts = foot_contacts(upright(source))
        ratio = stance_speed(onto_canonical(source)[0], contacts) / stance_speed(source, contacts)
        assert ratio <= 1.1, (name, ratio)


def round_trip_height(source: Motion, through: Motion) -> float:
    """How far a round trip ``source`` -> ``through``'s rig -> ``source``'s rig moves the whole
    body along ``source``'s up axis, mean over joints and frames, in % of its actor height."""
    back = retarget(retarget(source, through, plant_feet=False), source, plant_feet=False)
    conventions = read_conventions(source, find_joint_map(source.skeleton))
    from expressive_mocap.rotations import quat

    up = quat.rotate(quat.conjugate(conventions.rotation()), np.array([0.0, 1.0, 0.0]))
    lift = (back.positions() - source.positions()) @ up
    return 100 * float(np.abs(lift).mean()) / em.actor_height(source.skeleton)


@pytest.mark.parametrize("rig", ["cmu", "mixamo", "game", "smpl"])
def test_a_round_trip_comes_back_at_its_own_height(rig):
    """A -> Bandai -> A: the stance feet are put where the target's own stand (the median over its
    contacts), not at its floor (a low percentile of every frame), so the body comes back at its
    own height (real walks came back 0.3-0.8 % of the actor's height low, these 0.06-0.09 %)."""
    source = synthetic_walk(rig, seconds=4.0).motion
    assert round_trip_height(source, synthetic_walk("bandai", seconds=4.0).motion) < 0.02


@pytest.mark.real_data
@pytest.mark.parametrize("name", ["m21_walk", "m21_female-walk", "cmu_scaled_131_03", "cmu_01_01"])
def test_real_round_trips_come_back_at_their_own_height(other_dir, bandai2_dir, name):
    bandai = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh")
    assert round_trip_height(em.read_bvh(other_dir / f"{name}.bvh"), bandai) < 0.2
