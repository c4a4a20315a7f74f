"""Every command reads SMPL/AMASS parameter files (.npz) with --body-model, and `preprocess` takes
folders and archives of them: each gives what it gives for the BVH that `convert` writes of the
same file. The motion is a walk (the synthetic SMPL-rig walk written as AMASS parameters, on a
body model whose rest joints are that rig's), so the methods have something to read."""

from __future__ import annotations

import io
import json
import re
import shutil
import tarfile
import zipfile

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.skeletons import synthetic_walk
from expressive_mocap.skeletons.smpl import JOINT_NAMES, read_smpl

Z_UP_TO_Y_UP = Rotation.from_euler("x", -90, degrees=True)


def amass_walk(seconds: float = 4.0, step: float = 1.0) -> tuple[dict, dict, np.ndarray]:
    """The synthetic SMPL-rig walk (Z up) as AMASS parameters, the body model whose rest joints
    (Y up, in SMPL's joint order) are that rig's, and the walk's joint positions turned Y up in
    SMPL's order. ``step`` scales the walk's rotations (another walk of the same body)."""
    walk = synthetic_walk("smpl", seconds=seconds).motion
    names = JOINT_NAMES[24]
    order = [walk.skeleton.index(name) for name in names]
    parents = np.array([-1] + [order.index(walk.skeleton.parents[j]) for j in order[1:]])
    rest_z = np.zeros((24, 3))
    for k, j in enumerate(order):
        offset = walk.skeleton.offsets[j]
        rest_z[k] = offset if parents[k] < 0 else rest_z[parents[k]] + offset
    rest_y = Z_UP_TO_Y_UP.apply(rest_z)
    model = {
        "v_template": rest_y,
        "shapedirs": np.zeros((24, 3, 10)),
        "J_regressor": np.eye(24),
        "kintree_table": np.stack([np.where(parents < 0, 2**32 - 1, parents), np.arange(24)]).astype(np.uint32),
    }
    local = Rotation.from_quat(walk.rotations[:, order].reshape(-1, 4)).as_rotvec().reshape(-1, 24, 3) * step
    poses = np.empty_like(local)
    for k in range(24):  # the rig's rotations in the Y-up model's axes; the root's back in AMASS's Z-up world
        turned = Z_UP_TO_Y_UP * Rotation.from_rotvec(local[:, k]) * Z_UP_TO_Y_UP.inv()
        poses[:, k] = (Z_UP_TO_Y_UP.inv() * turned if k == 0 else turned).as_rotvec()
    trans = walk.translations[:, order[0]] - rest_y[0]
    params = {
        "poses": poses.reshape(len(poses), 72),
        "trans": trans,
        "betas": np.zeros(10),
        "gender": np.array("neutral"),
        "mocap_framerate": np.array(walk.fps),
    }
    expected = Z_UP_TO_Y_UP.apply(walk.positions()[:, order].reshape(-1, 3)).reshape(-1, 24, 3)
    return params, model, expected


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """walk.npz (a walk), other.npz (another), model.npz, and walk.bvh: `convert`'s BVH of walk.npz."""
    folder = tmp_path_factory.mktemp("smpl")
    params, model, _ = amass_walk()
    np.savez(folder / "model.npz", **model)
    np.savez(folder / "walk.npz", **params)
    np.savez(folder / "other.npz", **amass_walk(3.0, step=1.3)[0])
    assert main(["convert", str(folder / "walk.npz"), "--body-model", str(folder / "model.npz"), "-o",
                 str(folder / "walk.bvh")]) == 0  # fmt: skip
    return folder


def test_the_walk_as_parameters_is_the_rigs_walk():
    params, model, expected = amass_walk()
    motion = read_smpl(params, model)
    ours = motion.positions()[:, [motion.skeleton.index(name) for name in JOINT_NAMES[24]]]
    assert np.abs(ours - expected).max() < 1e-9


def _same_motion(a, b, tolerance=1e-6):
    """Two motions equal: joints, frame rate, rotations (either sign) and translations."""
    assert a.skeleton.names == b.skeleton.names and a.n_frames == b.n_frames
    assert a.frame_time == pytest.approx(b.frame_time, rel=1e-12)
    dots = np.abs(np.sum(a.rotations * b.rotations, axis=-1))
    assert 1 - dots.min() < tolerance
    assert np.abs(a.translations - b.translations).max() < tolerance * max(1.0, np.abs(a.translations).max())


_NUMBER = re.compile(r"-?\d+(?:\.\d*)?(?:e[-+]?\d+)?")


def _same_text(a: str, b: str) -> None:
    """The same words, and numbers that agree to print precision (within 1e-6, or a last digit:
    a value printed to 3 significant digits may round either way)."""
    assert _NUMBER.sub("#", a) == _NUMBER.sub("#", b), (a, b)
    for x, y in zip(_NUMBER.findall(a), _NUMBER.findall(b)):
        digits = x.split("e")[0].split(".")[-1] if "." in x else ""
        step = 10.0 ** -len(digits) * (10.0 ** int(x.split("e")[1]) if "e" in x else 1.0)
        assert abs(float(x) - float(y)) <= max(1e-6, 1.01 * step), (x, y)


def _table(path):
    return np.genfromtxt(path, delimiter=",", names=True)


# Each command with the input's place marked IN and its outputs' OUT: run on walk.npz with
# --body-model and on walk.bvh, the printed text (the file's name aside) and every file alike.
COMMANDS = {
    "info": (["info", "IN"], []),
    "skeleton": (["skeleton", "IN", "--json"], []),
    "footsteps": (["footsteps", "IN"], []),
    "positions": (["positions", "IN", "-o", "OUT.npz"], ["OUT.npz"]),
    "decouple": (["decouple", "IN", "-o", "OUT"], ["OUT_body.bvh", "OUT_expressive.bvh", "OUT_activity.csv"]),
    "modulate": (["modulate", "IN", "--scale", "0.5", "-o", "OUT.bvh"], ["OUT.bvh"]),
    "exaggerate": (["exaggerate", "--input", "IN", "--to", "3", "-o", "OUT.bvh"], ["OUT.bvh"]),
    "retarget": (["retarget", "IN", "--to", "TARGET", "-o", "OUT.bvh"], ["OUT.bvh"]),
}


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_commands_read_a_parameter_file_as_its_bvh(files, tmp_path, capsys, command):
    args, outputs = COMMANDS[command]
    target = tmp_path / "target.bvh"
    em.write_bvh(synthetic_walk("mixamo", seconds=1.0).motion, target)
    results = {}
    for kind, source, extra in (("npz", files / "walk.npz", ["--body-model", str(files / "model.npz")]),
                                ("bvh", files / "walk.bvh", [])):  # fmt: skip
        out = tmp_path / kind
        line = [
            str(source) if a == "IN" else str(target) if a == "TARGET" else a.replace("OUT", str(out)) for a in args
        ]
        assert main(line + extra) == 0, capsys.readouterr().err
        text = capsys.readouterr().out.replace(str(source), "IN").replace(str(out), "OUT")
        results[kind] = (text.replace("walk.npz", "IN").replace("walk.bvh", "IN"), out)
    (npz_text, npz_out), (bvh_text, bvh_out) = results["npz"], results["bvh"]
    _same_text(npz_text, bvh_text)
    for name in outputs:
        a, b = (str(o) + name[3:] for o in (npz_out, bvh_out))
        if name.endswith(".bvh"):
            _same_motion(em.read_bvh(a), em.read_bvh(b))
        elif name.endswith(".csv"):
            x, y = _table(a), _table(b)
            assert x.dtype.names == y.dtype.names
            assert max(np.abs(x[n] - y[n]).max() for n in x.dtype.names) < 1e-6
        else:
            with np.load(a) as x, np.load(b) as y:
                assert sorted(x.files) == sorted(y.files)
                for key in x.files:
                    if x[key].dtype.kind == "f":
                        assert np.abs(x[key] - y[key]).max() < 1e-6, key
                    else:
                        assert (x[key] == y[key]).all(), key


def test_exaggerate_picks_the_walks_model_for_a_parameter_file(files, tmp_path, capsys):
    out = tmp_path / "out.bvh"
    line = ["exaggerate", "--input", str(files / "walk.npz"), "--body-model", str(files / "model.npz")]
    assert main([*line, "--to", "3", "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert "walk (energy)" in said.splitlines()[0], said
    assert (
        em.read_bvh(out).skeleton.names == read_smpl(str(files / "walk.npz"), str(files / "model.npz")).skeleton.names
    )


def _archive(kind: str, folder, members: dict[str, bytes]):
    """``members`` (name -> bytes) as a folder, a zip or a tar.gz under ``folder``; its path."""
    folder.mkdir(parents=True, exist_ok=True)
    if kind == "folder":
        root = folder / "clips"
        for name, data in members.items():
            (root / name).parent.mkdir(parents=True, exist_ok=True)
            (root / name).write_bytes(data)
        return root
    if kind == "zip":
        path = folder / "clips.zip"
        with zipfile.ZipFile(path, "w") as archive:
            for name, data in members.items():
                archive.writestr(name, data)
        return path
    path = folder / "clips.tar.gz"
    with tarfile.open(path, "w:gz") as archive:
        for name, data in sorted(members.items()):  # a tar is read in its own order
            info = tarfile.TarInfo(name)
            info.size = len(data)
            archive.addfile(info, io.BytesIO(data))
    return path


@pytest.mark.parametrize("kind", ["folder", "zip", "tar"])
def test_preprocess_takes_parameter_files_as_their_bvh(files, tmp_path, kind):
    model = str(files / "model.npz")
    np.savez(tmp_path / "shape.npz", betas=np.zeros(10), gender=np.array("neutral"))  # AMASS's: no motion
    converted = {}
    for name in ("walk", "other"):
        assert (
            main(["convert", str(files / f"{name}.npz"), "--body-model", model, "-o", str(tmp_path / f"{name}.bvh")])
            == 0
        )
        converted[f"s1/{name}.bvh"] = (tmp_path / f"{name}.bvh").read_bytes()
    params = {f"s1/{n}.npz": (files / f"{n}.npz").read_bytes() for n in ("walk", "other")}
    params["s1/shape.npz"] = (tmp_path / "shape.npz").read_bytes()
    keep = "positions,rotations,features,contacts,activity"
    source = _archive(kind, tmp_path / "p", params)
    ours = em.preprocess(source, tmp_path / "ours", keep, "", canonical=True, smpl_model=model, progress=False)
    theirs = em.preprocess(_archive("folder", tmp_path / "b", converted), tmp_path / "theirs", keep, "",
                           canonical=True, progress=False)  # fmt: skip
    assert ours.clips_ok == theirs.clips_ok == 2 and ours.clips_failed == 0
    a, b = em.load_dataset(tmp_path / "ours"), em.load_dataset(tmp_path / "theirs")
    assert [c["name"] for c in a.manifest["clips"]] == ["s1/other", "s1/walk"]
    for k in ("positions", "rotations", "features", "contacts", "activity"):
        assert np.array_equal(getattr(a, k), getattr(b, k)), k
    manifest = json.loads((tmp_path / "ours" / "manifest.json").read_text())
    assert manifest["options"]["smpl_model"] == str((files / "model.npz").resolve())
    # Without the body model the parameter files are not clips: nothing read.
    assert em.preprocess(source, tmp_path / "none", progress=False).clips_ok == 0


def test_preprocess_with_a_bad_body_model_or_clip(files, tmp_path, capsys):
    source = tmp_path / "clips"
    source.mkdir()
    (source / "walk.npz").write_bytes((files / "walk.npz").read_bytes())
    (source / "broken.npz").write_bytes(b"PK\x03\x04 not a zip")
    out = tmp_path / "out"
    assert main(["preprocess", str(source), "-o", str(out), "--body-model", str(tmp_path / "missing.npz")]) == 1
    err = capsys.readouterr().err
    assert "missing.npz" in err and "body model" in err and not out.exists()
    assert main(["preprocess", str(source), "-o", str(out), "-q"]) == 1
    assert "--body-model" in capsys.readouterr().err
    shutil.rmtree(out)
    assert main(["preprocess", str(source), "-o", str(out), "--body-model", str(files / "model.npz"), "-q"]) == 0
    said = capsys.readouterr()
    assert "broken.npz" in said.out + said.err
    assert [c["name"] for c in em.load_dataset(out).manifest["clips"]] == ["walk"]
