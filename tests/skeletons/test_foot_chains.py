"""Rigs whose foot chain is named or built otherwise (a fore-foot or ball joint in place of a toe,
no toe joint at all, a heel joint) still get feet, floor and contacts, and retarget as the same
rig with a plain toe does: the toes' place is read from the End Site where no joint holds it."""

from __future__ import annotations

import numpy as np
import pytest

from expressive_mocap import Body, Motion, Skeleton
from expressive_mocap.body.contacts import floor_of, foot_contacts
from expressive_mocap.skeletons import retarget, synthetic_walk

SIDES = ("Left", "Right")


@pytest.fixture(scope="module")
def walk() -> Motion:
    return synthetic_walk("cmu", seconds=3.0).motion  # toes LeftToeBase, RightToeBase


@pytest.fixture(scope="module")
def bandai() -> Motion:
    return synthetic_walk("bandai", seconds=1.0).motion


def renamed(motion: Motion, names: dict[str, str]) -> Motion:
    s = motion.skeleton
    skeleton = Skeleton(tuple(names.get(n, n) for n in s.names), s.parents, s.offsets, s.channels, s.end_sites)
    return Motion(skeleton, motion.rotations, motion.translations, motion.frame_time)


def without_toes(motion: Motion) -> Motion:
    """The toe joints taken out, each foot ending in an End Site where its toe joint was."""
    s = motion.skeleton
    toes = [s.index(f"{side}ToeBase") for side in SIDES]
    keep = [j for j in range(s.n_joints) if j not in toes]
    index = {j: i for i, j in enumerate(keep)}
    sites = [(index[j], off) for j, off in s.end_sites if j in index]
    sites += [(index[int(s.parents[t])], tuple(s.offsets[t])) for t in toes]
    skeleton = Skeleton(
        tuple(s.names[j] for j in keep),
        np.array([index[int(s.parents[j])] if s.parents[j] >= 0 else -1 for j in keep]),
        s.offsets[keep],
        tuple(s.channels[j] for j in keep),
        tuple(sites),
    )
    return Motion(skeleton, motion.rotations[:, keep], motion.translations[:, keep], motion.frame_time)


def with_heels(motion: Motion) -> Motion:
    """A heel joint behind and below each ankle, the joints put back in depth-first order."""
    s = motion.skeleton
    shin = np.linalg.norm(s.offsets[s.index("LeftLeg")])  # heels scale with the rig
    heel = np.array([0.0, -0.12, -0.12]) * shin  # behind the ankle: this rig's toes point along +Z
    names = list(s.names) + [f"{side}Heel" for side in SIDES]
    parents = list(s.parents) + [s.index(f"{side}Foot") for side in SIDES]
    offsets = np.concatenate([s.offsets, [heel, heel]])
    channels = list(s.channels) + [s.channels[s.index(f"{side}Foot")][-3:] for side in SIDES]
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (motion.n_frames, 2, 1))
    rotations = np.concatenate([motion.rotations, identity], axis=1)
    translations = np.concatenate([motion.translations, np.broadcast_to(heel, (motion.n_frames, 2, 3))], axis=1)
    order: list[int] = []
    stack = [0]
    while stack:  # depth first, children in their order
        j = stack.pop()
        order.append(j)
        stack.extend(reversed([c for c in range(len(names)) if parents[c] == j]))
    index = {j: i for i, j in enumerate(order)}
    skeleton = Skeleton(
        tuple(names[j] for j in order),
        np.array([index[parents[j]] if parents[j] >= 0 else -1 for j in order]),
        offsets[order],
        tuple(channels[j] for j in order),
        tuple((index[j], off) for j, off in s.end_sites),
    )
    return Motion(skeleton, rotations[:, order], translations[:, order], motion.frame_time)


VARIANTS = {
    "ball": lambda m: renamed(m, {f"{s}ToeBase": f"{s}Ball" for s in SIDES}),
    "fore-foot": lambda m: renamed(m, {f"{s}ToeBase": f"{s}ForeFoot" for s in SIDES}),
    "no toe": without_toes,
    "heel": with_heels,
    "heel, no toe": lambda m: with_heels(without_toes(m)),
}


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_the_feet_are_the_ankles_and_a_heel_is_no_toe(walk, variant):
    motion = VARIANTS[variant](walk)
    names = motion.skeleton.names
    jmap = Body.of(motion.skeleton).joint_map
    for side in SIDES:
        assert names[jmap[f"{side.lower()}_foot"]] == f"{side}Foot"
        toes = names[jmap[f"{side.lower()}_toes"]] if f"{side.lower()}_toes" in jmap.joints else None
        assert toes == {"ball": f"{side}Ball", "fore-foot": f"{side}ForeFoot", "heel": f"{side}ToeBase"}.get(variant)
    roles = Body.of(motion.skeleton).roles
    assert [names[j] for j in roles.feet] == ["LeftFoot", "RightFoot"]


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_contacts_and_floor_of_the_feet_so_built(walk, variant):
    motion = VARIANTS[variant](walk)
    contacts, plain = foot_contacts(motion), foot_contacts(walk)
    # Without a toe joint the ankle alone tells contact: it lifts at heel-off, a little earlier.
    assert np.mean(contacts == plain) > (0.9 if "no toe" in variant else 0.999)
    if "no toe" in variant:  # the floor at the ankles' lowest, as every path reads it (kernels take joints)
        ankles = motion.positions()[:, list(Body.of(motion.skeleton).roles.feet), 1]
        assert floor_of(motion) == pytest.approx(np.percentile(ankles, 5.0))
    else:
        assert floor_of(motion) == pytest.approx(floor_of(walk), abs=1e-9)


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_a_foot_so_built_retargets_as_the_plain_toe_does(walk, bandai, variant):
    """Onto the Bandai body and back: the feet point and stand where the plain rig's do (the
    toeless foot's toes read from its End Site)."""
    motion = VARIANTS[variant](walk)
    plain, ours = retarget(walk, bandai), retarget(motion, bandai)
    _, a = plain.fk()
    _, b = ours.fk()
    s = bandai.skeleton
    for side in ("L", "R"):
        foot, toe = s.index(f"Foot_{side}"), s.index(f"Toes_{side}")
        u, v = a[:, toe] - a[:, foot], b[:, toe] - b[:, foot]
        cosine = np.sum(u * v, axis=1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        assert np.degrees(np.arccos(np.clip(cosine, -1, 1))).max() < 0.5, side
        assert np.abs(b[:, toe, 1] - a[:, toe, 1]).max() < 0.5  # cm
    back = retarget(ours, motion)  # onto the rig so built
    _, c = back.fk()
    _, d = motion.fk()
    feet = [motion.skeleton.index(f"{side}Foot") for side in SIDES]
    assert np.abs(c[:, feet, 1] - d[:, feet, 1]).mean() < 0.02 * Body.of(motion.skeleton).actor_height
