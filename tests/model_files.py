"""Small valid model files of both kinds, as their arrays and metadata: the base that
tests/utils/test_model_files.py and tools/fuzz_bvh.py tamper with."""

import io
import json

import numpy as np

from expressive_mocap._utils import model_files as em_io
from expressive_mocap.decoupling import body_model as em_model
from expressive_mocap.exaggeration.model import FORMAT, VERSION
from expressive_mocap.exaggeration.settings import REPRESENTATIONS


def small_models() -> dict[str, tuple[dict, dict]]:
    """(arrays, meta) of a tiny body model and a tiny exaggeration model, as their files hold them."""
    shipped, meta, _ = em_io.read_model_file(em_model.shipped_model_bytes(), "model")
    rng = np.random.default_rng(0)
    predicted = shipped["predicted"][:2]
    body = {
        "predicted": predicted,
        "hemispheres": shipped["hemispheres"][:2],
        "thigh_reference": shipped["thigh_reference"],
        "network.activations": np.array(["tanh", "linear"]),
        "network.0.weights": rng.normal(size=(19, 3)),
        "network.0.bias": rng.normal(size=3),
        "network.1.weights": rng.normal(size=(3, 8)),
        "network.1.bias": rng.normal(size=8),
    }
    J, D, T, r, P, K = 2, 7, 3, 2, 2, 2
    exag = {
        "parents": np.array([-1, 0]),
        "offsets": rng.normal(size=(J, 3)),
        "orders": np.array([[2, 0, 1], [2, 0, 1]], np.uint8),
        "weights": rng.uniform(size=D),
        "levels": np.array([1.0, 2.0]),
        "basis": rng.normal(size=(T, r)),
        "singular_values": np.array([2.0, 1.0]),
        "expressiveness": rng.uniform(size=(P, D)),
        "overall": rng.uniform(size=D),
        "key": np.ones(D, bool),
        "person_key": np.ones((P, D), bool),
        "mappings": rng.normal(size=(D, r, 2)),
        "reference": np.tile([0.0, 0.0, 0.0, 1.0], (J, 1)),
        "person_reference": np.tile([0.0, 0.0, 0.0, 1.0], (P, J, 1)),
        "lower": -np.ones(D),
        "upper": np.ones(D),
        "trajectories": rng.normal(size=(P, K, T, D)),
        "cycle_trajectories": rng.normal(size=(5, T, D)),
        "cycle_performance": np.array([[0, 0], [0, 1], [1, 0], [1, 1], [1, 1]]),
    }
    exag_meta = {
        "format": FORMAT,
        "version": VERSION,
        "joint_names": ["Hips", "Spine"],
        "dof_names": [f"{j}.{a}" for j in ("Hips", "Spine") for a in "xyz"] + ["Hips.height"],
        "height": 170.0,
        "hips": 0,
        "representation": REPRESENTATIONS[0],
        "energy": 0.99,
        "settings": {},
    }
    body_meta = dict(meta, joint_names=list(meta["joint_names"]), settings={}, report={})
    return {"body": (body, body_meta), "exaggeration": (exag, exag_meta)}


def npz(arrays: dict, meta) -> bytes:
    buffer = io.BytesIO()
    np.savez(buffer, meta=np.array(json.dumps(meta) if not isinstance(meta, str) else meta), **arrays)
    return buffer.getvalue()
