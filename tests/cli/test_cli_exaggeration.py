"""`exaggerate` on a file of another skeleton: edited on the model's body, carried back, its feet
planted on the file's own skeleton, and the report measured on the file written, in its names."""

from __future__ import annotations

import re

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.conventions import upright
from expressive_mocap.cli import main
from expressive_mocap.exaggeration import train
from expressive_mocap.exaggeration.edit import stance_foot_speed
from expressive_mocap.procedural import loaded_walk
from expressive_mocap.skeletons import synthetic_walk

LEVELS = (1.0, 2.0, 3.0)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    out = tmp_path_factory.mktemp("exaggerate")
    train([[loaded_walk(k, seconds=4.0) for k in LEVELS]], LEVELS).save(out / "model.npz")
    em.write_bvh(synthetic_walk("cmu", seconds=4.0).motion, out / "cmu.bvh")
    return out


@pytest.mark.parametrize("to", [1.0, 3.0])
def test_another_rigs_walk_is_measured_as_written(files, to, capsys):
    out = files / f"cmu_{to:g}.bvh"
    argv = ["exaggerate", "--model", str(files / "model.npz"), "--input", str(files / "cmu.bvh")]
    assert main([*argv, "--to", str(to), "--no-timing", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    line = next(line for line in text.splitlines() if "as written" in line)
    original, written = em.read_bvh(files / "cmu.bvh"), em.read_bvh(out)
    named = re.findall(r"([A-Za-z0-9_]+) [0-9.]+(?:,|$)", line.split("(degrees):")[1])
    assert named and set(named) <= set(original.skeleton.names)  # the file's own joint names
    measured = text.split("as written")[1]
    before, after = (float(v) for v in re.search(r"stance-foot speed ([0-9.e+-]+) -> ([0-9.e+-]+)", measured).groups())
    # What the report says is what the written file shows, and the feet stay planted.
    original, written = upright(original), upright(written)
    contacts = foot_contacts(original)
    assert before == pytest.approx(stance_foot_speed(original, contacts), rel=1e-2)
    assert after == pytest.approx(stance_foot_speed(written, contacts), rel=1e-2)
    assert after <= 1.2 * before
    changed = np.abs(written.rotations - original.rotations).max()
    assert changed > 1e-3  # the edit did something
