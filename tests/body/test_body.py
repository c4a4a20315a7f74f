"""A Body is found once per skeleton content and a Take keeps what is derived from its motion:
every command asks each finder (roles, joint map, heights) at most once per distinct skeleton."""

from __future__ import annotations

import collections

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap import Body, Take, write_bvh
from expressive_mocap.body import body as body_module
from expressive_mocap.body import contacts as contacts_module
from expressive_mocap.body import roles as roles_module
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.cli import main
from expressive_mocap.errors import ArgumentError, MocapError
from expressive_mocap.exaggeration import train
from expressive_mocap.motion import Skeleton
from expressive_mocap.procedural import loaded_walk, procedural_walk, walk_and_wave
from expressive_mocap.skeletons import synthetic_walk


def _copy(skeleton: Skeleton) -> Skeleton:
    """The same skeleton read again: equal content, another object."""
    return Skeleton(
        tuple(skeleton.names), skeleton.parents.copy(), skeleton.offsets.copy(), skeleton.channels, skeleton.end_sites
    )


def test_one_body_per_skeleton_content_and_user_map():
    skeleton = procedural_walk(1.0).skeleton
    again = _copy(skeleton)
    assert again is not skeleton
    assert Body.of(again) is Body.of(skeleton)
    moved = _copy(skeleton)
    moved.offsets.setflags(write=True)
    moved.offsets[3] *= 1.1  # a longer chest: another body
    assert Body.of(moved) is not Body.of(skeleton)
    with_map = Body.of(skeleton, {"left_toe": "Toes_L"})
    assert with_map is not Body.of(skeleton) and with_map is Body.of(again, {"left_toe": "Toes_L"})


def test_the_actor_height_has_one_definition_and_the_commands_report_it(capsys):
    skeleton = procedural_walk(1.0).skeleton
    body = Body.of(skeleton)
    joints, _ = skeleton.rest_positions()
    spine = sum(np.linalg.norm(skeleton.offsets[j]) for j in body.roles.spine[1:])
    assert body.actor_height == pytest.approx(body.hips_rest_height + spine)
    assert em.actor_height(skeleton) == body.actor_height
    assert 139 < body.actor_height < 143  # cm: hips standing + the spine to the head joint


def test_a_skeleton_whose_roles_cannot_be_found_says_so_once_asked():
    walk = procedural_walk(1.0)
    names = tuple(f"j{j}" for j in range(walk.skeleton.n_joints))
    anonymous = Skeleton(names, walk.skeleton.parents, walk.skeleton.offsets, walk.skeleton.channels)
    body = Body.of(anonymous)  # finding nothing yet
    with pytest.raises(MocapError):
        _ = body.roles
    with pytest.raises(ArgumentError, match="`skeleton`"):
        Body.of("not a skeleton")  # type: ignore[arg-type]


def test_a_take_keeps_its_contacts_and_refuses_another_skeletons_body():
    walk = procedural_walk(2.0)
    take = Take.of(walk)
    assert Take.of(take) is take
    first = foot_contacts(take)
    first[:] = False  # the caller's copy: the take's own is untouched
    np.testing.assert_array_equal(foot_contacts(take), foot_contacts(walk))
    assert foot_contacts(take).any()
    other = synthetic_walk("cmu", seconds=1.0).motion
    with pytest.raises(ArgumentError, match="`body`"):
        Take(walk, Body.of(other.skeleton))
    assert not take.positions.flags.writeable


class _Counted:
    """Wraps a finder, recording the skeleton content of every call."""

    def __init__(self, function, skeleton_of=lambda *args: args[0]):
        self.function, self.skeleton_of = function, skeleton_of
        self.calls: collections.Counter = collections.Counter()

    def __call__(self, *args, **kwargs):
        self.calls[self.skeleton_of(*args).content_key] += 1
        return self.function(*args, **kwargs)


@pytest.fixture
def counted(monkeypatch):
    """The three finders, counted, with no Body kept from earlier tests."""
    monkeypatch.setattr(body_module, "_BODIES", body_module.Kept(body_module.KEPT))
    finders = {
        "map": _Counted(body_module.find_joint_map),
        "roles": _Counted(roles_module.JointRoles.by_names.__func__, lambda cls, skeleton: skeleton),
        "heights": _Counted(body_module.rest_heights),
    }
    monkeypatch.setattr(body_module, "find_joint_map", finders["map"])
    monkeypatch.setattr(roles_module, "find_joint_map", finders["map"])
    monkeypatch.setattr(roles_module.JointRoles, "by_names", classmethod(finders["roles"]))
    monkeypatch.setattr(body_module, "rest_heights", finders["heights"])
    return finders


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    out = tmp_path_factory.mktemp("finders")
    pair = walk_and_wave(seconds=3.0)
    write_bvh(pair.walk, out / "walk.bvh")
    write_bvh(pair.waving, out / "wave.bvh")
    write_bvh(synthetic_walk("cmu", seconds=2.0).motion, out / "cmu.bvh")
    levels = [1.0, 2.0, 3.0]
    train([[loaded_walk(k, seconds=3.0) for k in levels]], levels).save(out / "model.npz")
    write_bvh(loaded_walk(2.0, seconds=3.0), out / "loaded.bvh")
    return out


COMMANDS = {
    "mix": ["mix", "--body", "walk.bvh", "--expressive", "wave.bvh", "-o", "out.bvh"],
    "blend": ["blend", "walk.bvh", "wave.bvh", "--body-window", "20:40", "--expressive-window", "10:30", "-o", "b.bvh"],
    "modulate": ["modulate", "wave.bvh", "--scale", "1.5", "-o", "out.bvh"],
    "decouple": ["decouple", "wave.bvh", "-o", "parts"],
    "footsteps": ["footsteps", "walk.bvh"],
    "skeleton": ["skeleton", "walk.bvh", "wave.bvh", "cmu.bvh"],
    "retarget": ["retarget", "cmu.bvh", "--to", "walk.bvh", "-o", "out.bvh"],
    "exaggerate": ["exaggerate", "--model", "model.npz", "--input", "loaded.bvh", "--to", "3", "-o", "out.bvh"],
    "exaggerate-other-rig": ["exaggerate", "--model", "model.npz", "--input", "cmu.bvh", "--to", "3", "-o", "o.bvh"],
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_each_finder_runs_once_per_skeleton_in_a_command(command, counted, files, monkeypatch, capsys):
    monkeypatch.chdir(files)
    assert main(COMMANDS[command]) == 0, capsys.readouterr().err
    for finder, counter in counted.items():
        repeated = {key[0][:2]: n for key, n in counter.calls.items() if n > 1}  # (joint names) -> calls
        assert not repeated, f"{command}: the {finder} finder ran {max(repeated.values())} times for one skeleton"
    assert sum(counted["roles"].calls.values()) + sum(counted["map"].calls.values()) > 0


def test_contacts_of_a_take_are_detected_once(monkeypatch):
    take = Take.of(procedural_walk(2.0))
    calls = []
    detect = contacts_module._contacts
    monkeypatch.setattr(contacts_module, "_contacts", lambda *a: calls.append(1) or detect(*a))
    for _ in range(3):
        foot_contacts(take)
    foot_contacts(take, causal=True)
    assert len(calls) == 2  # offline once, causal once
