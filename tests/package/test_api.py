"""The Python API's rough edges: the package's top-level names (importing it loads no model and no
dataset reader) and one-line reprs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import expressive_mocap as em
from expressive_mocap.dataset import load_dataset
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


def test_importing_the_package_loads_neither_numpy_nor_the_methods():
    code = "import sys, expressive_mocap; print(' '.join(sorted(sys.modules)))"
    loaded = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env={"PYTHONPATH": str(PYTHON)}
    ).stdout.split()
    for heavy in (
        "numpy",
        "expressive_mocap.exaggeration",
        "expressive_mocap.decoupling.body_model",
        "expressive_mocap.decoupling.algebra",
        "expressive_mocap.dataset",
    ):
        assert heavy not in loaded


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
    assert f"test MSE {model.report.fine_tuned.test_mse:.3g}" in text
