"""Choosing the kernels: environment variable, Python call, and life without the extension."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import expressive_mocap as em
from expressive_mocap import backend, reference


def python(code: str, **env):
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env={**os.environ, **env})


def test_environment_variable_picks_the_backend():
    result = python("import expressive_mocap as em; print(em.get_backend())", EXPRESSIVE_MOCAP_BACKEND="numpy")
    assert result.stdout.strip() == "numpy"
    if em.rust_available():
        assert (
            python(
                "import expressive_mocap as em; print(em.get_backend())", EXPRESSIVE_MOCAP_BACKEND="rust"
            ).stdout.strip()
            == "rust"
        )


def test_use_backend_restores_the_previous_choice():
    before = em.get_backend()
    with em.use_backend("numpy"):
        assert em.get_backend() == "numpy" and backend.kernels() is reference
    assert em.get_backend() == before
    with pytest.raises(em.MocapError):
        em.set_backend("gpu")


WITHOUT_EXTENSION = """
import sys
from pathlib import Path
sys.modules["expressive_mocap._core"] = None  # as if the extension had never been built
import expressive_mocap as em
print(em.rust_available(), em.get_backend())
motion = em.read_bvh(sys.argv[1])
print(motion.n_frames, round(float(motion.positions()[-1, 5, 1]), 6))
try:
    em.set_backend("rust")
except em.MocapError as error:
    print("refused:", error)
"""


def test_package_works_without_the_extension(mixed_path):
    result = subprocess.run([sys.executable, "-c", WITHOUT_EXTENSION, str(mixed_path)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[0] == "False numpy"
    expected = em.read_bvh(mixed_path)
    assert lines[1] == f"4 {round(float(expected.positions()[-1, 5, 1]), 6)}"
    assert lines[2].startswith("refused:") and "not installed" in lines[2]


def test_backend_option_after_the_command(mixed_path, capsys, monkeypatch):
    from expressive_mocap import backend as backend_module
    from expressive_mocap.cli import main

    chosen = []
    real = backend_module.set_backend
    monkeypatch.setattr(backend_module, "set_backend", lambda name: (chosen.append(name), real(name)))
    with em.use_backend("auto"):
        chosen.clear()
        assert main(["info", str(mixed_path), "--backend", "numpy"]) == 0
        assert main(["--backend", "numpy", "info", str(mixed_path)]) == 0
        assert main(["--backend", "numpy", "info", str(mixed_path), "--backend", "auto"]) == 0  # the later one wins
    assert chosen == ["numpy", "numpy", "auto"]


def test_a_bad_backend_in_the_environment_is_a_one_line_error_not_an_import_failure(mixed_path):
    env = {**os.environ, "EXPRESSIVE_MOCAP_BACKEND": "bogus", "PYTHONPATH": str(Path(em.__file__).parent.parent)}
    imported = subprocess.run(
        [sys.executable, "-c", "import expressive_mocap"], env=env, capture_output=True, text=True
    )
    assert imported.returncode == 0, imported.stderr
    ran = subprocess.run(
        [sys.executable, "-m", "expressive_mocap.cli", "info", str(mixed_path)], env=env, capture_output=True, text=True
    )
    assert ran.returncode == 1 and ran.stderr.count("\n") == 1
    assert "got 'bogus' (from the environment variable EXPRESSIVE_MOCAP_BACKEND)" in ran.stderr
