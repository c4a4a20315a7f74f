"""Model files are data: tampered and truncated files of both kinds (body model, exaggeration
model) are refused with a MocapError naming the file and the problem, never loaded half-right
and never raising anything else."""

import io
import zipfile

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap._utils.model_files import MAX_MODEL_BYTES
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.exaggeration import ExaggerationModel
from model_files import npz, small_models

MODELS = small_models()
LOAD = {"body": BodyModel.load, "exaggeration": ExaggerationModel.load}


def refused(kind, data, words):
    with pytest.raises(em.MocapError) as caught:
        LOAD[kind](data)
    assert str(caught.value).startswith("<bytes>: ") and words in str(caught.value), str(caught.value)


@pytest.mark.parametrize("kind", LOAD)
def test_the_small_models_load(kind):
    LOAD[kind](npz(*MODELS[kind]))


def array_cases():
    for kind, (arrays, _) in MODELS.items():
        for key in arrays:
            yield kind, key


@pytest.mark.parametrize("kind, key", list(array_cases()))
def test_every_array_missing_or_tampered_is_refused(kind, key):
    arrays, meta = MODELS[kind]
    value = arrays[key]
    refused(kind, npz({k: v for k, v in arrays.items() if k != key}, meta), "")
    if value.dtype.kind in "fiu" and value.size and key != "network.activations":
        refused(kind, npz({**arrays, key: value.reshape(-1)[:-1]}, meta), "")  # wrong shape
        refused(kind, npz({**arrays, key: value.astype(str)}, meta), repr(key))  # text
        refused(kind, npz({**arrays, key: value.astype(np.complex128)}, meta), repr(key))
        if value.dtype.kind == "f":
            poisoned = value.copy()
            poisoned.reshape(-1)[-1] = np.nan
            refused(kind, npz({**arrays, key: poisoned}, meta), repr(key))  # NaN weights, offsets...
            poisoned.reshape(-1)[-1] = np.inf
            refused(kind, npz({**arrays, key: poisoned}, meta), repr(key))


@pytest.mark.parametrize("kind", LOAD)
def test_an_extra_array_is_refused(kind):
    arrays, meta = MODELS[kind]
    refused(kind, npz({**arrays, "payload": np.arange(3)}, meta), "unexpected arrays")


@pytest.mark.parametrize("kind", LOAD)
@pytest.mark.parametrize(
    "meta, words",
    [
        ("{", "not a readable"),
        ("[1, 2]", "not an object"),
        ('"text"', "not an object"),
        ("null", "not an object"),
        ("{}", "version"),
    ],
)
def test_unreadable_or_foreign_metadata_is_refused(kind, meta, words):
    refused(kind, npz(MODELS[kind][0], meta), words)


@pytest.mark.parametrize(
    "kind, field, value",
    [
        (kind, field, value)
        for kind in LOAD
        for field, value in [
            ("joint_names", 3),
            ("joint_names", ["a", 1]),
            ("settings", [1]),
            ("height", "tall"),
            ("hips", 9),
            ("representation", []),
        ]
        if field in MODELS[kind][1]  # the fields each kind of model has
    ],
)
def test_metadata_of_the_wrong_type_is_refused(kind, field, value):
    arrays, meta = MODELS[kind]
    refused(kind, npz(arrays, {**meta, field: value}), "")


@pytest.mark.parametrize("kind", LOAD)
def test_inconsistent_skeleton_or_indices_are_refused(kind):
    arrays, meta = MODELS[kind]
    if kind == "body":
        refused(kind, npz({**arrays, "predicted": arrays["predicted"][[0, 0]]}, meta), "predicted")
        refused(kind, npz({**arrays, "predicted": arrays["predicted"].astype(float)}, meta), "predicted")
    else:
        refused(kind, npz({**arrays, "parents": np.array([0, -1])}, meta), "inconsistent")
        refused(kind, npz({**arrays, "orders": np.array([[0, 0, 1], [2, 0, 1]], np.uint8)}, meta), "inconsistent")
        owners = arrays["cycle_performance"]
        refused(
            kind, npz({**arrays, "cycle_performance": owners + [[2, 0]]}, meta), "cycle_performance"
        )  # no such person
        refused(
            kind, npz({**arrays, "cycle_performance": owners[[0, 1, 2, 2, 2]]}, meta), "cycle_performance"
        )  # a performance without cycles
        refused(kind, npz({**arrays, "cycle_performance": owners - 1}, meta), "cycle_performance")
        refused(kind, npz({**arrays, "cycle_performance": owners.astype(float)}, meta), "cycle_performance")


@pytest.mark.parametrize("kind", LOAD)
def test_truncated_files_are_refused(kind):
    data = npz(*MODELS[kind])
    for end in [0, 10, len(data) // 3, len(data) // 2, len(data) - 30, len(data) - 1]:
        refused(kind, data[:end], "not a readable")


def _with_member(data: bytes, name: str, member: bytes) -> bytes:
    buffer = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as source, zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as target:
        for item in source.namelist():
            target.writestr(item, source.read(item))
        target.writestr(name, member)
    return buffer.getvalue()


@pytest.mark.parametrize("kind", LOAD)
def test_pickles_and_huge_arrays_are_refused_before_loading(kind):
    data = npz(*MODELS[kind])
    pickled = io.BytesIO()
    np.save(pickled, np.array([{"run": "os.system"}], dtype=object), allow_pickle=True)
    refused(kind, _with_member(data, "evil.npy", pickled.getvalue()), "Python objects")
    # A zip bomb: a header claiming 1 TB of zeros (the data need not even be there).
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": (2**37,)})
    refused(kind, _with_member(data, "bomb.npy", header.getvalue()), f"more than {MAX_MODEL_BYTES} bytes")


@pytest.mark.parametrize(
    ("field", "value", "words"),
    [
        ("height", float("nan"), "the actor's height must be a positive length, got nan"),
        ("height", 0.0, "the actor's height must be a positive length, got 0.0"),
        ("height", -1.0, "the actor's height must be a positive length, got -1.0"),
    ],
)
def test_an_exaggeration_model_of_no_height_is_refused(field, value, words):
    arrays, meta = MODELS["exaggeration"]
    refused("exaggeration", npz(arrays, {**meta, field: value}), words)


def test_an_exaggeration_model_of_one_intensity_is_refused():
    arrays, meta = MODELS["exaggeration"]
    refused("exaggeration", npz({**arrays, "levels": np.array([2.0, 2.0])}, meta), "two different intensities")


@pytest.fixture(scope="module")
def walk_model():
    """An exaggeration model of the demo's walks on the Bandai-like skeleton, with its joint map."""
    from expressive_mocap.exaggeration import train
    from expressive_mocap.procedural import loaded_walk

    return train([[loaded_walk(k) for k in (1.0, 2.0)]], (1.0, 2.0))


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"head": "Hips"}, "'Hips' plays two roles, hips and head"),
        ({"left_hand": "Nowhere"}, "no joint named 'Nowhere'"),
        ({"spine": ["Hips"]}, "the spine's joint 'Hips' does not hang below the hips"),
    ],
)
def test_an_exaggeration_model_whose_joint_map_does_not_fit_is_refused(walk_model, change, words):
    """Its map is how motions of other skeletons reach it: a bad one is the file's error at load,
    not a traceback (two roles on one joint) or "applies to its own skeleton" (a missing joint)."""
    bad = ExaggerationModel.load(walk_model.to_bytes())
    assert bad.joint_map  # found in training
    bad.joint_map = {**bad.joint_map, **change}
    with pytest.raises(em.MocapError) as caught:
        ExaggerationModel.load(bad.to_bytes())
    message = str(caught.value)
    assert "its joint map does not fit its own skeleton" in message and words in message, message
