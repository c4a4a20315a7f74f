"""The methods' models on any skeleton, through the canonical body: an edit computed on the body
the models were trained on, carried back onto the user's own skeleton as per-joint changes of
world orientation (:class:`~expressive_mocap.skeletons.canonical.Carried`)."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from conftest import FixedFloor
from expressive_mocap.body import find_joint_map
from expressive_mocap.cli import main
from expressive_mocap.decoupling import BodyModel, decompose, modulate
from expressive_mocap.decoupling.algebra import Decomposition, split
from expressive_mocap.procedural import loaded_walk
from expressive_mocap.skeletons import retarget, synthetic_walk
from expressive_mocap.skeletons.canonical import Carried, canonical_rig
from expressive_mocap.skeletons.retargeting import retarget_rigs
from expressive_mocap.skeletons.rig import Rig

_LIMB = [("upper_arm", "forearm"), ("forearm", "hand"), ("upper_leg", "lower_leg"), ("clavicle", "upper_arm")]
BONES = [(f"{s}_{a}", f"{s}_{b}") for s in ("left", "right") for a, b in _LIMB]


def directions(motion: em.Motion) -> np.ndarray:
    jmap = find_joint_map(motion.skeleton)
    p = motion.positions()
    v = np.stack([p[:, jmap[b]] - p[:, jmap[a]] for a, b in BONES], axis=1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def worst_angle(a, b) -> float:
    return float(np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1, 1))).max())


@pytest.mark.parametrize("rig", ["smpl", "cmu", "game", "mixamo"])
def test_an_unedited_body_carries_back_to_the_motion_itself(rig):
    motion = synthetic_walk(rig, wave="left").motion
    carried = Carried(motion)
    assert carried.body.skeleton is canonical_rig().skeleton
    back = carried.back(carried.body)
    np.testing.assert_allclose(back.positions(), motion.positions(), atol=1e-9 / 0.01)
    np.testing.assert_allclose(back.translations, motion.translations, atol=1e-9)


def test_an_edit_carried_back_is_the_edited_body_on_the_users_skeleton():
    """Taking the wave out of the waving walk on the game rig (Z up, A pose, twist bones): the
    edit made on the canonical body and carried back puts every mapped bone where retargeting the
    edited body onto the game rig does, and the user's twist bones and offsets stay theirs."""
    model = BodyModel.load()
    game = synthetic_walk("game", wave="left").motion
    carried = Carried(game)
    edited = modulate(carried.body, 0.0, model)
    ours = carried.back(edited, hinges=False)
    theirs = retarget_rigs(edited, canonical_rig(), Rig.of(game), plant_feet=False)
    assert worst_angle(directions(ours), directions(theirs)) < 1e-4
    # With the user's hinge limits (the default) nothing moves: the arm brought down bends no
    # hinge past straight on this rig (carried-back edits that do are limited in test_hinges).
    limited = carried.back(edited)
    np.testing.assert_array_equal(limited.rotations, ours.rotations)
    assert ours.skeleton is game.skeleton
    twist = game.skeleton.index("upperarm_twist_01_l")
    np.testing.assert_allclose(ours.rotations[:, twist], game.rotations[:, twist], atol=1e-12)  # follows its bone
    # The edit did something: the raised left arm came down, as on the Bandai rig's own walk.
    assert worst_angle(directions(ours), directions(game)) > 30
    bandai = synthetic_walk("bandai", wave="left").motion
    on_bandai = retarget_rigs(modulate(bandai, 0.0, model), Rig.of(bandai), Rig.of(game), plant_feet=False)
    # Not to the degree: the game rig's three spine joints share the turn Bandai's two split unevenly.
    assert worst_angle(directions(ours), directions(on_bandai)) < 10


def test_decouple_modulate_and_mix_take_any_skeleton(tmp_path, capsys):
    smpl, game = tmp_path / "smpl.bvh", tmp_path / "game.bvh"
    em.write_bvh(synthetic_walk("smpl", wave="left").motion, smpl)
    em.write_bvh(synthetic_walk("game").motion, game)
    assert main(["decouple", str(smpl), "-o", str(tmp_path / "parts")]) == 0
    body = em.read_bvh(tmp_path / "parts_body.bvh")
    assert body.skeleton.names == em.read_bvh(smpl).skeleton.names  # written on the user's skeleton
    assert main(["modulate", str(smpl), "--scale", "0", "-o", str(tmp_path / "calm.bvh")]) == 0
    calm = em.read_bvh(tmp_path / "calm.bvh")
    np.testing.assert_allclose(calm.skeleton.offsets, em.read_bvh(smpl).skeleton.offsets, atol=1e-6)
    # The SMPL rig's wave laid onto the game rig's walk: written on the game rig, its left hand up.
    assert main(["mix", "--body", str(game), "--expressive", str(smpl), "-o", str(tmp_path / "mixed.bvh")]) == 0
    mixed, walk = em.read_bvh(tmp_path / "mixed.bvh"), em.read_bvh(game)
    jmap = find_joint_map(mixed.skeleton)
    up = 2  # the game rig is Z up
    raised = mixed.positions()[:, jmap["left_hand"], up] - walk.positions()[:, jmap["left_hand"], up]
    assert mixed.skeleton.names == walk.skeleton.names and np.median(raised) > 20  # cm


def test_exaggerate_takes_another_skeleton_than_the_models(tmp_path):
    levels = {k: [loaded_walk(k, seconds=3.0, wobble=0.3, seed=10 * p + k) for p in (0, 1)] for k in (1, 2, 3)}
    paths = []
    for k, walks in levels.items():
        for p, walk in enumerate(walks):
            paths += ["--level", str(k)] if p == 0 else []
            path = tmp_path / f"level{k}_{p}.bvh"
            em.write_bvh(walk, path)
            paths.append(str(path))
    model = tmp_path / "walks.npz"
    assert main(["rank", *paths, "-o", str(model)]) == 0
    game = synthetic_walk("game").motion
    sources = {"bandai": levels[1][0], "game": retarget(levels[1][0], game, plant_feet=False)}
    out = {}
    for name, motion in sources.items():
        em.write_bvh(motion, tmp_path / f"{name}_level1.bvh")
        argv = ["exaggerate", "--model", str(model), "--input", str(tmp_path / f"{name}_level1.bvh"), "--to", "3"]
        assert main([*argv, "--no-foot-lock", "-o", str(tmp_path / f"{name}_level3.bvh")]) == 0
        out[name] = em.read_bvh(tmp_path / f"{name}_level3.bvh")
    assert out["game"].skeleton.names == game.skeleton.names
    # A real change, and nearly the exaggeration of the model's own skeleton, carried over (the
    # spine's turn is shared over three joints on the game rig, two on the model's).
    theirs = retarget(out["bandai"], game, plant_feet=False)
    assert worst_angle(directions(out["game"]), directions(sources["game"])) > 2
    assert worst_angle(directions(out["game"]), directions(theirs)) < 10


def test_blend_from_a_game_rig_walk_into_a_bandai_wave(tmp_path):
    game, wave = tmp_path / "game.bvh", tmp_path / "wave.bvh"
    em.write_bvh(synthetic_walk("game").motion, game)
    em.write_bvh(synthetic_walk("bandai", wave="left").motion, wave)
    out = tmp_path / "blend.bvh"
    assert main(["blend", str(game), str(wave), "--body-window", "30:60", "-o", str(out)]) == 0
    blended = em.read_bvh(out)
    assert blended.skeleton.names == em.read_bvh(game).skeleton.names
    jmap = find_joint_map(blended.skeleton)
    hand = blended.positions()[:, jmap["left_hand"], 2] - blended.positions()[:, jmap["hips"], 2]  # Z up, cm
    assert hand[:20].max() < 10 < hand[-20:].min()  # walking arms down, then waving


def test_the_shipped_models_activity_agrees_across_skeletons_and_finds_the_wave():
    model = BodyModel.load()
    names = canonical_rig().skeleton.names
    activity = {}
    for rig in ("bandai", "cmu", "mixamo", "smpl", "game", "lafan"):
        motion = synthetic_walk(rig, wave="left").motion
        if abs(motion.fps - 30) > 1e-6:
            motion = motion.resample(fps=30)  # the model reads features at the rate it was trained at
        activity[rig] = decompose(Carried(motion).body, model).activity.mean(axis=0)
    for rig, values in activity.items():
        assert np.abs(values - activity["bandai"]).max() < 0.05, rig
        left, right = (values[names.index(f"UpperArm_{s}")] for s in "LR")
        assert left > 0.5 > 0.1 > right, (rig, left, right)  # the waving arm, not the other


def test_the_model_commands_take_a_map_file(tmp_path, capsys):
    game = tmp_path / "game.bvh"
    em.write_bvh(synthetic_walk("game", wave="left").motion, game)
    good, bad = tmp_path / "good.toml", tmp_path / "bad.json"
    good.write_text('chest = "spine_02"\n')
    bad.write_text('{"elbow": "lowerarm_l"}')
    out = tmp_path / "calm.bvh"
    assert main(["modulate", str(game), "--scale", "0", "--map", str(good), "-o", str(out)]) == 0
    unmapped = em.read_bvh(out)
    assert main(["modulate", str(game), "--scale", "0", "-o", str(out)]) == 0
    # The chest given one joint lower changes how the body is read, so the result (by about 0.1
    # degree: the chest's frame is read from the shoulders and head either way); the same command
    # twice gives the same numbers.
    assert np.abs(unmapped.rotations - em.read_bvh(out).rotations).max() > 1e-5
    capsys.readouterr()
    for argv in (["modulate", str(game), "--scale", "0"], ["decouple", str(game)], ["calibrate", str(game)]):
        assert main([*argv, "--map", str(bad), "-o", str(tmp_path / "x")]) == 1
        assert "bad.json: unknown role 'elbow'" in capsys.readouterr().err


def test_a_model_trained_on_another_skeleton_exaggerates_a_bandai_walk(tmp_path):
    """Rank on the game rig (its walks are the loaded walks carried over), exaggerate a walk of
    the Bandai skeleton with it: the walk goes through the model's own body (its mean pose on its
    skeleton) and back, and changes as the game rig's own walk does."""
    game = synthetic_walk("game").motion
    argv = []
    for k in (1, 2, 3):
        argv += ["--level", str(k)]
        for p in (0, 1):
            walk = retarget(loaded_walk(k, seconds=3.0, wobble=0.3, seed=10 * p + k), game, plant_feet=False)
            em.write_bvh(walk, tmp_path / f"game{k}_{p}.bvh")
            argv.append(str(tmp_path / f"game{k}_{p}.bvh"))
    assert main(["rank", *argv, "-o", str(tmp_path / "game_walks.npz")]) == 0
    bandai = loaded_walk(1, seconds=3.0, wobble=0.3, seed=1)
    em.write_bvh(bandai, tmp_path / "bandai1.bvh")
    outputs = {}
    for name in ("bandai1", "game1_0"):
        argv = ["exaggerate", "--model", str(tmp_path / "game_walks.npz"), "--input", str(tmp_path / f"{name}.bvh")]
        assert main([*argv, "--to", "3", "--no-foot-lock", "-o", str(tmp_path / f"{name}_3.bvh")]) == 0
        outputs[name] = em.read_bvh(tmp_path / f"{name}_3.bvh")
    assert outputs["bandai1"].skeleton.names == bandai.skeleton.names
    assert worst_angle(directions(outputs["bandai1"]), directions(bandai)) > 2
    theirs = retarget(outputs["game1_0"], bandai, plant_feet=False)
    assert worst_angle(directions(outputs["bandai1"]), directions(theirs)) < 10


def test_carrying_through_a_body_in_other_axes():
    """The body a motion is carried through may have axes of its own (a Z-up model body facing
    -Y): an edit there comes back onto the user's skeleton as retargeting it would put it."""
    from expressive_mocap.rotations import quat

    game, smpl = synthetic_walk("game").motion, synthetic_walk("smpl").motion
    carried = Carried(game, None, Rig.of(smpl))
    np.testing.assert_allclose(carried.back(carried.body).positions(), game.positions(), atol=1e-8)
    rotations = carried.body.rotations.copy()
    arm = carried.body.skeleton.index("left_shoulder")
    rotations[:, arm] = quat.mul(quat.about("X", np.full(len(rotations), 40.0)), rotations[:, arm])
    edited = em.Motion(carried.body.skeleton, rotations, carried.body.translations, carried.body.frame_time)
    ours = carried.back(edited)
    theirs = retarget_rigs(edited, Rig.of(smpl), Rig.of(game), plant_feet=False)
    assert worst_angle(directions(ours), directions(theirs)) < 1e-4
    assert worst_angle(directions(ours), directions(game)) > 20


def test_render_decouples_a_file_of_another_skeleton(tmp_path):
    """`render --decoupled` and `--modulated` go through the model's body and draw the parts on the
    file's own skeleton (before: the model refused the 35-joint game rig)."""
    game = tmp_path / "game.bvh"
    em.write_bvh(synthetic_walk("game", wave="left", seconds=1.0).motion, game)
    for how in ("--decoupled", "--modulated"):
        out = tmp_path / f"game{how}.png"
        assert main(["render", str(game), how, "-o", str(out)]) == 0
        assert out.read_bytes().startswith(b"\x89PNG")


def test_the_streaming_decoupler_takes_another_skeleton():
    """Frame by frame, a waving walk on the game rig is decoupled as the whole clip is through the
    model's body (with the rig read from the first frame and the floor at 0, as a stream reads
    them; to 1e-9), its body mechanics come back on the rig's own joints, and the wave is found on
    the waving arm."""
    from expressive_mocap.decoupling import StreamingDecoupler
    from expressive_mocap.rotations import quat

    model = BodyModel.load()
    game = synthetic_walk("game", wave="left", seconds=3.0).motion
    stream = StreamingDecoupler(model, game.skeleton, game.frame_time)
    pushed = [stream.push(game.rotations[f], game.translations[f]) for f in range(game.n_frames)]
    body, expressive, activity = (np.array(x) for x in zip(*pushed))
    carried = Carried(game, source=Rig.of(game[:1])._replace(untrusted=frozenset()), stand=False)
    # The stream splits each frame as it comes: the offline split without its smoothing in time
    # (and without the toes set by the clip's stance, which a stream cannot know ahead).
    on_body = carried.body
    predicted = FixedFloor(model, 0.0).predict_streamed(on_body, stream.capacity)
    offline = Decomposition(on_body, *split(on_body.rotations, predicted, trunk=model.trunk, arms=model.arms))
    np.testing.assert_allclose(activity, offline.activity, atol=1e-9)
    assert body.shape == game.rotations.shape
    np.testing.assert_allclose(body, carried.back(offline.body_motion()).rotations, atol=1e-9)
    np.testing.assert_allclose(quat.mul(expressive, body), game.rotations, atol=1e-9)  # E B = O
    names = model.joint_names
    assert activity[:, names.index("UpperArm_L")].mean() > 0.5 > 0.1 > activity[:, names.index("UpperArm_R")].mean()


def test_an_exaggeration_model_records_its_skeletons_map(tmp_path):
    """`rank` records the joint map it found (or was given with --map) in the model file, and a
    motion of another skeleton reaches the model through that map: a chest given one joint lower
    by the map file is the chest of the model's body."""
    from expressive_mocap.exaggeration import ExaggerationModel
    from expressive_mocap.skeletons.canonical import carried_for

    argv = []
    for k in (1, 2):
        argv += ["--level", str(k)]
        for p in (0, 1):
            walk = retarget(loaded_walk(k, seconds=3.0, wobble=0.3, seed=10 * p + k), synthetic_walk("game").motion)
            em.write_bvh(walk, tmp_path / f"game{k}_{p}.bvh")
            argv.append(str(tmp_path / f"game{k}_{p}.bvh"))
    (tmp_path / "map.json").write_text('{"chest": "spine_02"}')
    assert main(["rank", *argv, "-o", str(tmp_path / "found.npz")]) == 0
    assert main(["rank", *argv, "--map", str(tmp_path / "map.json"), "-o", str(tmp_path / "given.npz")]) == 0
    found, given = (ExaggerationModel.load(tmp_path / f"{n}.npz") for n in ("found", "given"))
    assert found.joint_map["chest"] == "spine_03" and found.joint_map["left_upper_leg"] == "thigh_l"
    assert given.joint_map["chest"] == "spine_02"
    carried = carried_for(loaded_walk(1, seconds=2.0), given)
    assert carried.target.skeleton.names[carried.target.jmap["chest"]] == "spine_02"
