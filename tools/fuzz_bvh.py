"""Coverage-guided fuzzing (atheris, libFuzzer) of the whole BVH reader and of the model loaders.

    pip install -e .[fuzz]                                     # atheris
    nice -n 19 python tools/fuzz_bvh.py bvh CORPUS_DIR -atheris_runs=1000000 -max_len=4096
    python tools/fuzz_bvh.py bvh --compare CORPUS_DIR -atheris_runs=100000   # Rust and NumPy must agree
    python tools/fuzz_bvh.py model CORPUS_DIR -atheris_runs=100000          # BodyModel and ExaggerationModel

Arguments after the target are libFuzzer's (``-atheris_runs``, ``-max_total_time``, ``-seed``,
``-timeout``, ``-rss_limit_mb``, corpus folders); an empty corpus folder is first filled with
seeds (the test BVH files, tests/hostile_files.py, small model files). Each ``bvh`` input is read
with :func:`expressive_mocap.read_bvh`: it must give a Motion of finite, unit rotations that writes
and reads back the same, or a BVHError; ``--compare`` also reads it with the other backend, which
must agree. Each ``model`` input is either raw bytes or (first byte odd) a small model file with
some arrays and metadata tampered as the input says; both loaders must return a model or raise a
MocapError. Anything else (another exception, a crash, a hang past ``-timeout``, memory past
``-rss_limit_mb``) is a finding that libFuzzer saves as ``crash-*``, ``timeout-*`` or ``oom-*``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import atheris
import numpy as np

with atheris.instrument_imports():
    import expressive_mocap as em
    from expressive_mocap import exaggeration
    from expressive_mocap.decoupling import body_model as em_model

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO / "tests"))


# ----------------------------------------------------------------------------- BVH reader


def outcome(data: bytes):
    try:
        return em.read_bvh(data)
    except em.BVHError as error:
        return error


def check_bvh(data: bytes, compare: bool) -> None:
    result = outcome(data)
    if isinstance(result, em.Motion):
        rotations = result.rotations
        assert np.isfinite(rotations).all() and np.allclose(np.linalg.norm(rotations, axis=-1), 1.0, atol=1e-9)
        assert np.isfinite(result.translations).all()
        again = em.read_bvh(em.bvh_bytes(result))  # what we read, we write and read back
        assert again.skeleton.names == result.skeleton.names and again.n_frames == result.n_frames
        assert np.allclose(np.abs(np.sum(again.rotations * rotations, axis=-1)), 1.0, atol=1e-9)
    if compare:
        with em.use_backend("numpy"):
            twin = outcome(data)
        if isinstance(result, em.Motion):
            assert isinstance(twin, em.Motion), twin
            np.testing.assert_allclose(twin.rotations, result.rotations, atol=1e-12)
        else:
            assert isinstance(twin, em.BVHError) and twin.line == result.line, (result, twin)


def bvh_seeds() -> list[bytes]:
    from hostile_files import cases

    seeds = [p.read_bytes() for p in sorted((REPO / "tests" / "data").glob("*.bvh"))]
    return seeds + [data for data, _ in cases().values() if len(data) <= 65536]


# ----------------------------------------------------------------------------- model files


def tampered(fdp: atheris.FuzzedDataProvider, models: dict) -> bytes:
    from model_files import npz

    """One of the small model files with arrays and metadata changed as the input says."""
    arrays, meta = models[fdp.PickValueInList(sorted(models))]
    arrays, meta = dict(arrays), json.loads(json.dumps(meta))
    for _ in range(fdp.ConsumeIntInRange(1, 4)):
        try:
            arrays, meta = tamper_once(fdp, arrays, meta)
        except (TypeError, ValueError):  # a change numpy cannot make (e.g. floats to datetimes): skip it
            pass
    return npz(arrays, meta)


def tamper_once(fdp: atheris.FuzzedDataProvider, arrays: dict, meta):
    action = fdp.ConsumeIntInRange(0, 7)
    key = fdp.PickValueInList(sorted(arrays)) if arrays else "x"
    if action == 0:
        arrays.pop(key, None)
    elif action == 1:
        arrays["extra_" + fdp.ConsumeUnicodeNoSurrogates(8)] = np.arange(fdp.ConsumeIntInRange(0, 5))
    elif action == 2 and key in arrays:
        kind = fdp.PickValueInList(["float32", "int8", "uint64", "bool", "complex128", "U3", "S2", "datetime64[s]"])
        arrays[key] = arrays[key].astype(kind) if kind not in ("U3", "S2") else arrays[key].astype(str).astype(kind)
    elif action == 3 and key in arrays and arrays[key].size:
        flat = arrays[key].astype(np.float64).ravel()
        flat[fdp.ConsumeIntInRange(0, flat.size - 1)] = fdp.PickValueInList([np.nan, np.inf, -np.inf, 1e308, -1.0, 0.0])
        arrays[key] = flat.reshape(arrays[key].shape)
    elif action == 4 and key in arrays:
        shape = [fdp.ConsumeIntInRange(0, 4) for _ in range(fdp.ConsumeIntInRange(0, 4))]
        arrays[key] = np.resize(arrays[key], shape)
    elif action == 5 and isinstance(meta, dict) and meta:
        field = fdp.PickValueInList(sorted(meta))
        meta[field] = fdp.PickValueInList([None, 1, -1, 1.5, "x", [], ["a", 1], {}, True, [0] * 3, "Hips"])
    elif action == 6:
        meta = fdp.PickValueInList([[], 3, "null", "{", '"text"', json.dumps(meta)[: fdp.ConsumeIntInRange(0, 40)]])
    elif action == 7 and key in arrays:
        arrays[key] = np.asarray(arrays[key]).T
    return arrays, meta


def check_model(data: bytes, models: dict) -> None:
    if data[:1] and data[0] % 2 == 1:
        data = tampered(atheris.FuzzedDataProvider(data[1:]), models)
    for load in (em_model.BodyModel.load, exaggeration.ExaggerationModel.load):
        try:
            load(bytes(data))
        except em.MocapError:
            pass


# ----------------------------------------------------------------------------- main


def main() -> None:
    target = sys.argv[1] if len(sys.argv) > 1 else ""
    if target not in ("bvh", "model"):
        sys.exit(__doc__)
    compare = "--compare" in sys.argv
    args = [sys.argv[0]] + [a for a in sys.argv[2:] if a != "--compare"]
    corpora = [Path(a) for a in args[1:] if not a.startswith("-")]
    if target == "bvh":
        em.set_backend("rust" if em.rust_available() else "numpy")
        seeds = bvh_seeds()

        def test_one(data: bytes) -> None:
            check_bvh(data, compare)

    else:
        from model_files import npz, small_models

        models = small_models()
        seeds = [npz(*m) for m in models.values()] + [b"\x01" + bytes(range(64))]

        def test_one(data: bytes) -> None:
            check_model(data, models)

    for corpus in corpora:
        corpus.mkdir(parents=True, exist_ok=True)
        if not any(corpus.iterdir()):
            for k, seed in enumerate(seeds):
                (corpus / f"seed-{k:03d}").write_bytes(seed)
    atheris.Setup(args, test_one)
    atheris.Fuzz()


if __name__ == "__main__":
    main()
