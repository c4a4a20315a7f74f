"""The Python API's rough edges: top-level names, write_bvh's input, one-line reprs, and a
Dataset that follows sequence and mapping conventions."""

from __future__ import annotations

import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.decoupling.algebra import decompose
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.procedural import procedural_walk

PYTHON = Path(em.__file__).resolve().parent.parent  # the package the tests import (installed in CI)


# ----------------------------------------------------------------------------- the package's names


def test_the_main_entry_points_are_importable_from_the_top_level():
    # Failed before with ImportError: none of these were exported.
    from expressive_mocap import BodyModel as body_model
    from expressive_mocap import ExaggerationModel
    from expressive_mocap import decompose as top_decompose
    from expressive_mocap import load_dataset as top_load_dataset
    from expressive_mocap.exaggeration import ExaggerationModel as exaggeration_itself

    assert top_decompose is decompose and body_model is BodyModel and top_load_dataset is load_dataset
    assert ExaggerationModel is exaggeration_itself
    assert {"BodyModel", "ExaggerationModel", "decompose", "load_dataset"} <= set(em.__all__) <= set(dir(em))
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        em.nonsense  # noqa: B018


def test_importing_the_package_does_not_load_the_models_or_the_dataset_reader():
    code = "import sys, expressive_mocap; print(' '.join(sorted(sys.modules)))"
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env={"PYTHONPATH": str(PYTHON)}
    ).stdout.split()
    for heavy in (
        "expressive_mocap.exaggeration",
        "expressive_mocap.decoupling.body_model",
        "expressive_mocap.decoupling.algebra",
        "expressive_mocap.dataset",
    ):
        assert heavy not in loaded


# ----------------------------------------------------------------------------- write_bvh


def test_write_bvh_of_a_decompositions_array_names_the_call_to_make(tmp_path):
    walk = procedural_walk(seconds=0.5)
    parts = decompose(walk, BodyModel.load())
    # Failed before with AttributeError: 'numpy.ndarray' object has no attribute 'skeleton'.
    with pytest.raises(em.MocapError) as raised:
        em.write_bvh(parts.body, tmp_path / "body.bvh")
    message = str(raised.value)
    assert "\n" not in message and "needs a Motion" in message and "parts.body_motion()" in message
    assert f"array {list(parts.body.shape)}" in message
    with pytest.raises(em.MocapError, match="got a Decomposition"):
        em.write_bvh(parts, tmp_path / "body.bvh")
    assert not (tmp_path / "body.bvh").exists()
    em.write_bvh(parts.body_motion(), tmp_path / "body.bvh")  # the call the message names works
    np.testing.assert_allclose(
        em.read_bvh(tmp_path / "body.bvh").positions(), parts.body_motion().positions(), atol=1e-6
    )


# ----------------------------------------------------------------------------- reprs


def test_skeleton_and_body_model_print_on_one_line():
    walk = procedural_walk(seconds=0.2)
    # Failed before: the dataclass reprs printed every offset / weight (thousands of characters).
    text = repr(walk.skeleton)
    assert text == "Skeleton(22 joints, root 'joint_Root', 5 End Sites, 132 channels)"
    model = BodyModel.load()
    text = repr(model)
    assert "\n" not in text and len(text) < 200, text
    assert "22-joint skeleton" in text and "19-300-300-80" in text
    assert f"test MSE {model.report['fine_tuned']['test_mse']:.3g}" in text


# ----------------------------------------------------------------------------- Dataset


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("api") / "clips"
    folder.mkdir()
    for k, seconds in enumerate((0.6, 0.4, 0.5)):
        em.write_bvh(procedural_walk(seconds=seconds), folder / f"walk_{k}.bvh")
    out = folder.parent / "ds"
    preprocess(folder, out, keep="positions,contacts", progress=False)
    return load_dataset(out)


def test_a_dataset_is_a_sequence_of_clips(dataset):
    ds = dataset
    # Failed before: ds[0] raised KeyError (ds[...] took kinds only) and iteration failed with it.
    first, last = ds[0], ds[-1]
    assert len(ds) == 3 and ds.kinds == ("positions", "contacts")
    assert (first.name, last.name) == ("walk_0", "walk_2") and first.index == 0 and last.index == 2
    assert [clip.name for clip in ds] == ds.names
    assert ds["walk_1"].index == 1 and "walk_1" in ds and "walk_9" not in ds
    for i, clip in enumerate(ds):
        rows = slice(ds.offsets[i], ds.offsets[i + 1])
        assert clip.frames == ds.clips[i]["frames"] == rows.stop - rows.start
        assert dict(clip).keys() == {"positions", "contacts"}
        np.testing.assert_array_equal(clip["positions"], ds.positions[rows])
        assert clip.contacts is clip["contacts"] and np.shares_memory(clip.positions, ds.arrays["positions"])
    with pytest.raises(IndexError, match="clip 3 of a dataset of 3 clips"):
        ds[3]
    with pytest.raises(KeyError, match="no clip named 'walk_9'"):
        ds["walk_9"]
    with pytest.raises(AttributeError, match="kinds are positions, contacts"):
        ds.features  # noqa: B018
    with pytest.raises(KeyError, match="kinds are positions, contacts"):
        first["features"]


def test_a_kind_name_as_a_key_still_gives_the_whole_array_with_a_warning(dataset):
    with pytest.warns(DeprecationWarning, match=r"ds\.positions"):
        whole = dataset["positions"]
    assert whole is dataset.positions is dataset.arrays["positions"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        dataset["walk_0"]  # a clip name: no warning
