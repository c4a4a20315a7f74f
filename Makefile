# The project's checks as named targets; `make check` (the README's test command, and what CI
# runs) is all of them in order, stopping at the first failure. Each target is described in
# docs/development.md.

# The Python folders ruff checks: those of pyproject.toml's [tool.ruff] `src` that exist here.
PY_DIRS := $(wildcard python tests benches experiments tools)
# What Blender's `bpy` wheel needs to import (the test that Blender reads our files).
BLENDER_LIBS := libx11-6 libxrender1 libxfixes3 libxi6 libxkbcommon0 libsm6 libgl1

.PHONY: help check setup lint types rust test test-numpy2
# One target after the other, in the order given, even under `make -j`.
.NOTPARALLEL:

help:
	@echo "make check        setup lint types rust test test-numpy2, in that order (what CI runs)"
	@echo "make setup        Blender's X11/GL libraries (apt-get, as root) and pip install '.[test]'"
	@echo "make lint         cargo fmt --check, cargo clippy (with and without python), ruff check and format"
	@echo "make types        mypy, and stubtest of the extension's stub"
	@echo "make rust         the Rust unit tests"
	@echo "make test         the Python test suite (NumPy 1, Blender; without the PyTorch tests)"
	@echo "make test-numpy2  the suite again in .venv-numpy2: the newest NumPy 2 and PyTorch, no Blender"

check: setup lint types rust test test-numpy2

setup:
	apt-get update -qq && apt-get install -y -qq --no-install-recommends $(BLENDER_LIBS)
	pip install '.[test]'

lint:
	cargo fmt --check
	cargo clippy -q -- -D warnings
	cargo clippy -q --features python -- -D warnings
	ruff check $(PY_DIRS)
	ruff format --check $(PY_DIRS)

types:
	mypy
	python -m mypy.stubtest expressive_mocap._core

rust:
	cargo test --release -q

test:
	python -m pytest -m 'not torch'

test-numpy2:
	python -m venv .venv-numpy2
	.venv-numpy2/bin/pip install -q --no-cache-dir '.[test-core,torch]' 'numpy>=2'
	.venv-numpy2/bin/python -m pytest -m 'not blender'
