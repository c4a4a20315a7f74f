"""SMPL-family parameter files (AMASS .npz) read on a synthetic body model with the real keys and
shapes (no model is downloaded): the joints of our motion against the model's own forward pass,
written in an independent form here, and the BVH that `convert` writes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.errors import ArgumentError, ModelError
from expressive_mocap.skeletons.smpl import JOINT_NAMES, read_smpl

# SMPL's body: parents and rough rest offsets from them (metres, Y up, facing +Z, left is +X).
_BODY = [
    (-1, (0.0, 0.92, 0.0)),
    (0, (0.07, -0.08, 0.0)),
    (0, (-0.07, -0.08, 0.0)),
    (0, (0.0, 0.1, -0.02)),
    (1, (0.03, -0.38, 0.0)),
    (2, (-0.03, -0.38, 0.0)),
    (3, (0.0, 0.13, 0.0)),
    (4, (0.0, -0.4, -0.04)),
    (5, (0.0, -0.4, -0.04)),
    (6, (0.0, 0.05, 0.02)),
    (7, (0.02, -0.05, 0.12)),
    (8, (-0.02, -0.05, 0.12)),
    (9, (0.0, 0.21, -0.03)),
    (9, (0.07, 0.11, -0.01)),
    (9, (-0.07, 0.11, -0.01)),
    (12, (0.0, 0.09, 0.05)),
    (13, (0.1, 0.03, -0.01)),
    (14, (-0.1, 0.03, -0.01)),
    (16, (0.26, -0.01, -0.02)),
    (17, (-0.26, -0.01, -0.02)),
    (18, (0.25, 0.01, 0.0)),
    (19, (-0.25, 0.01, 0.0)),
]


def _tree(joints: int, rng) -> tuple[np.ndarray, np.ndarray]:
    """Parents and rest joint places of SMPL (24), SMPL-H (52) or SMPL-X (55: the jaw and eyes
    under the head before the hands)."""
    parents = [p for p, _ in _BODY]
    offsets = [np.array(o) for _, o in _BODY]
    if joints == 24:
        parents += [20, 21]
        offsets += [np.array([0.09, -0.01, 0.0]), np.array([-0.09, -0.01, 0.0])]
    else:
        if joints == 55:
            parents += [15, 15, 15]
            offsets += [np.array([0.0, -0.02, 0.05]), np.array([0.03, 0.04, 0.07]), np.array([-0.03, 0.04, 0.07])]
        for wrist, side in ((20, 1.0), (21, -1.0)):
            for finger in range(5):  # index, middle, pinky, ring, thumb: three joints each
                base = len(parents)
                spread = np.array([side * 0.09, -0.005, 0.03 - 0.015 * finger])
                for k in range(3):
                    parents.append(wrist if k == 0 else base + k - 1)
                    offsets.append(spread if k == 0 else np.array([side * 0.03, 0.0, 0.0]) + rng.normal(0, 0.003, 3))
    rest = np.zeros((joints, 3))
    for j, (p, o) in enumerate(zip(parents, offsets)):
        rest[j] = o if p < 0 else rest[p] + o
    return np.array(parents), rest


def body_model(joints: int, seed: int = 0, betas: int = 16) -> dict[str, np.ndarray]:
    """A synthetic SMPL-like model: eight vertices about each joint, the regressor a random convex
    combination of them, small shape directions, and the other arrays of a real model file."""
    rng = np.random.default_rng(seed)
    parents, rest = _tree(joints, rng)
    per = 8
    template = np.repeat(rest, per, axis=0) + rng.normal(0, 0.03, (joints * per, 3))
    regressor = np.zeros((joints, joints * per))
    for j in range(joints):
        w = rng.uniform(0.2, 1.0, per)
        regressor[j, j * per : (j + 1) * per] = w / w.sum()
    vertices = len(template)
    table = np.stack([parents, np.arange(joints)]).astype(np.uint32)  # the root's parent: 2^32 - 1
    return {
        "v_template": template,
        "shapedirs": rng.normal(0, 0.01, (vertices, 3, betas)),
        "J_regressor": regressor,
        "kintree_table": table,
        "weights": np.eye(joints)[np.arange(vertices) // per],
        "posedirs": rng.normal(0, 0.001, (vertices, 3, 9 * (joints - 1))),
        "f": rng.integers(0, vertices, (2 * vertices, 3)).astype(np.uint32),
    }


def amass_params(joints: int, frames: int = 40, seed: int = 1, betas: int = 16) -> dict[str, np.ndarray]:
    """AMASS-style parameters: random poses within 0.5 rad, the root's turned upright first (+90
    degrees about X: the model's rest pose is Y up, AMASS's world Z up), a walk along +Y at 1.2 m/s;
    the frame rate spelt as AMASS's SMPL-X files spell it for 55 joints."""
    rng = np.random.default_rng(seed)
    t = np.arange(frames) / 120.0
    trans = np.stack([0.05 * np.sin(4 * t), 1.2 * t, 0.9 + 0.02 * np.sin(8 * t)], axis=1)
    poses = rng.uniform(-0.5, 0.5, (frames, 3 * joints))
    upright = Rotation.from_euler("x", 90, degrees=True) * Rotation.from_rotvec(poses[:, :3])
    poses[:, :3] = upright.as_rotvec()
    return {
        "poses": poses,
        "trans": trans,
        "betas": rng.normal(0, 1.0, betas),
        "gender": np.array("female"),
        # AMASS's SMPL-X files spell it mocap_frame_rate
        ("mocap_frame_rate" if joints == 55 else "mocap_framerate"): np.array(120.0),
        "dmpls": np.zeros((frames, 8)),
    }


def model_joints(params: dict, model: dict) -> np.ndarray:
    """The body model's own forward pass, Z up: rest joints from the shape, global transforms
    G_j = G_parent [R_j | J_j - J_parent], the root at J_0, everything moved by trans."""
    b = min(len(params["betas"]), model["shapedirs"].shape[2])
    rest = model["J_regressor"] @ (model["v_template"] + model["shapedirs"][..., :b] @ params["betas"][:b])
    parents = model["kintree_table"][0].astype(np.int64)
    frames, joints = len(params["poses"]), len(rest)
    out = np.zeros((frames, joints, 3))
    for f in range(frames):
        matrices = Rotation.from_rotvec(params["poses"][f].reshape(joints, 3)).as_matrix()
        globals_ = []
        for j in range(joints):
            local = np.eye(4)
            local[:3, :3] = matrices[j]
            local[:3, 3] = rest[j] - (rest[parents[j]] if j else 0.0)
            globals_.append(local if j == 0 else globals_[parents[j]] @ local)
            out[f, j] = globals_[j][:3, 3] + params["trans"][f]
    return out


def z_up(positions: np.ndarray) -> np.ndarray:
    """Our Y-up positions back in AMASS's Z-up world: (x, y, z) -> (x, -z, y)."""
    return np.stack([positions[..., 0], -positions[..., 2], positions[..., 1]], axis=-1)


def smpl_order(motion, joints: int) -> np.ndarray:
    """Our positions in SMPL's joint order (ours are depth first, as BVH nests them)."""
    return motion.positions()[:, [motion.skeleton.index(name) for name in JOINT_NAMES[joints]]]


def save(path, arrays: dict) -> str:
    np.savez(path, **arrays)
    return str(path)


@pytest.mark.parametrize("joints", [24, 52, 55])
def test_joints_match_the_models_forward_pass(joints):
    model, params = body_model(joints), amass_params(joints)
    motion = read_smpl(params, model)
    names, parents = motion.skeleton.names, motion.skeleton.parents
    assert sorted(names) == sorted(JOINT_NAMES[joints]) and names[:2] == ("pelvis", "left_hip")
    smpl_parents = model["kintree_table"][0].astype(np.int64)
    for j, name in enumerate(JOINT_NAMES[joints][1:], start=1):
        assert names[parents[names.index(name)]] == JOINT_NAMES[joints][smpl_parents[j]], name
    assert motion.frame_time == pytest.approx(1 / 120)
    assert motion.n_frames == 40
    expected = model_joints(params, model)
    ours = smpl_order(motion, joints)
    assert np.abs(z_up(ours) - expected).max() < 1e-6
    # Y up: the head is above the pelvis in every frame (the poses bend the spine 0.5 rad at most a joint),
    # and the walk along AMASS's +Y goes along our -Z.
    head = JOINT_NAMES[joints].index("head")
    rise = ours[:, head, 1] - ours[:, 0, 1]
    assert (rise > 0).all() and rise.mean() > 0.3, rise
    assert ours[-1, 0, 2] - ours[0, 0, 2] == pytest.approx(-1.2 * 39 / 120, abs=0.05)


def test_betas_change_the_skeleton_and_only_the_common_ones_count():
    model, params = body_model(24, betas=10), amass_params(24, betas=16)
    motion = read_smpl(params, model)  # 16 betas, a model with 10 directions: the first 10
    assert np.abs(z_up(smpl_order(motion, 24)) - model_joints(params, model)).max() < 1e-6
    flat = read_smpl({**params, "betas": np.zeros(16)}, model)
    assert np.abs(flat.skeleton.offsets - motion.skeleton.offsets).max() > 1e-3


@pytest.mark.parametrize("joints", [24, 52, 55])
def test_convert_writes_a_bvh_that_reads_back(tmp_path, joints, capsys):
    model, params = body_model(joints), amass_params(joints)
    model_path, params_path = save(tmp_path / "model.npz", model), save(tmp_path / "walk_poses.npz", params)
    out = tmp_path / "walk.bvh"
    assert main(["convert", params_path, "--body-model", model_path, "-o", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    back = em.read_bvh(out)
    assert back.skeleton.names == read_smpl(params, model).skeleton.names
    assert back.fps == pytest.approx(120)
    assert np.abs(z_up(smpl_order(back, joints)) - model_joints(params, model)).max() < 1e-4
    # Every other command reads the BVH it wrote.
    assert main(["info", str(out)]) == 0


def test_frame_rate_from_fps_when_the_file_has_none(tmp_path):
    model, params = body_model(24), amass_params(24)
    del params["mocap_framerate"]
    assert read_smpl(params, model, fps=60).frame_time == pytest.approx(1 / 60)
    with pytest.raises(ArgumentError, match="mocap_framerate"):
        read_smpl(params, model)
    out = tmp_path / "a.bvh"
    args = ["convert", save(tmp_path / "p.npz", params), "--body-model", save(tmp_path / "m.npz", model)]
    assert main([*args, "-o", str(out), "--fps", "60"]) == 0
    assert em.read_bvh(out).fps == pytest.approx(60)


def _bad(tmp_path, case):
    """Parameter and model files with one thing wrong, and the words the error must hold."""
    model, params = body_model(24), amass_params(24)
    if case == "missing poses":
        del params["poses"]
        return params, model, ["params.npz", "'poses'"]
    if case == "other joint count":
        return params, body_model(52), ["model.npz", "52 joints", "24"]
    if case == "short trans":
        params["trans"] = params["trans"][:-1]
        return params, model, ["params.npz", "'trans'", "[40, 3]"]
    if case == "nan poses":
        params["poses"][3, 5] = np.nan
        return params, model, ["params.npz", "'poses'", "non-finite"]
    if case == "missing regressor":
        del model["J_regressor"]
        return params, model, ["model.npz", "'J_regressor'"]
    raise AssertionError(case)


_CASES = ["missing poses", "other joint count", "short trans", "nan poses", "missing regressor"]


@pytest.mark.parametrize("case", _CASES)
def test_bad_inputs_are_one_line_errors(tmp_path, capsys, case):
    params, model, words = _bad(tmp_path, case)
    out = tmp_path / "out.bvh"
    args = [save(tmp_path / "params.npz", params), "--body-model", save(tmp_path / "model.npz", model)]
    assert main(["convert", *args, "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and err.startswith("expressive-mocap: error:"), err
    assert all(w in err for w in words), err
    assert not out.exists()
    error = ModelError if "model.npz" == words[0] else ArgumentError
    with pytest.raises(error):
        read_smpl(str(tmp_path / "params.npz"), str(tmp_path / "model.npz"))


def test_body_model_with_a_bvh_or_missing_for_an_npz_is_an_error(tmp_path, capsys):
    model, params = body_model(24), amass_params(24)
    model_path, params_path = save(tmp_path / "model.npz", model), save(tmp_path / "p.npz", params)
    bvh = tmp_path / "walk.bvh"
    em.write_bvh(read_smpl(params, model), bvh)
    out = tmp_path / "out.bvh"
    assert main(["convert", str(bvh), "--body-model", model_path, "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--body-model" in err and "walk.bvh" in err, err
    assert main(["convert", params_path, "-o", str(out)]) == 1
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "--body-model" in err and "p.npz" in err, err
    assert not out.exists()


def test_pickled_arrays_are_never_loaded(tmp_path):
    model, params = body_model(24), amass_params(24)
    params["poses"] = params["poses"].astype(object)
    with pytest.raises(ArgumentError, match="not a readable"):
        read_smpl(save(tmp_path / "p.npz", params), save(tmp_path / "m.npz", model))
