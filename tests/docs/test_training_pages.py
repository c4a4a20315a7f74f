"""docs/training.md's code, run as written on the dataset the README's "for training" command
makes: the command's own options (read from README.md, mirror images and all) on eight
dataset-2 clips (four performances, two takes each; Bandai-Namco-Research-Motiondataset,
CC BY-NC 4.0) into a folder named as the command names it, then every ```python block of the
page in order, in one namespace, from that folder's parent. Each line whose comment gives a
dtype and shape (``# float32 [256, 64, 22, 3]``) is checked against what the code made: the
same dtype, the same shape but for a first axis no larger than the comment's (the last batch of
an epoch is smaller)."""

from __future__ import annotations

import os
import re
import shlex
from pathlib import Path

import pytest

from expressive_mocap.cli import main

REPO = Path(__file__).resolve().parents[2]
PAGE = "docs/training.md"
CLIPS = [  # four performances (dataset, content, style), two takes each
    f"dataset-2_{performance}_{take:03d}"
    for performance in ("walk_normal", "walk_elderly", "run_normal", "wave-left-hand_active")
    for take in (1, 2)
]
SHAPED = re.compile(r"^\s*(.+?)\s+#\s*(?:torch\.)?(float32|int64|bool) \[([\d, ]+)\]")


def training_command() -> list[str]:
    """The README tour's `expressive-mocap preprocess ...   # for training` line, split."""
    readme = (REPO / "README.md").read_text()
    [line] = [line for line in readme.splitlines() if "# for training" in line]
    words = shlex.split(line.split(" #")[0])
    assert words[:2] == ["expressive-mocap", "preprocess"]
    return words[2:]


def python_blocks() -> list[str]:
    return re.findall(r"```python\n(.*?)```", (REPO / PAGE).read_text(), re.S)


@pytest.fixture(scope="module")
def workdir(bandai2_dir, tmp_path_factory) -> Path:
    """The README's dataset of :data:`CLIPS`, in the folder its command names, under the returned
    folder."""
    root = tmp_path_factory.mktemp("training_page")
    args = training_command()
    source = args.pop(0)
    assert source == "Bandai-Namco-Research-Motiondataset-2/data"
    out = args[args.index("-o") + 1]
    assert "--mirror" in args, "the page's Mirror augmentation reads the mirror images"
    (root / "src").mkdir()
    for name in CLIPS:
        os.symlink(bandai2_dir / f"{name}.bvh", root / "src" / f"{name}.bvh")
    args[args.index("-o") + 1] = str(root / out)
    assert main(["preprocess", str(root / "src"), *args, "-q"]) == 0
    return root


def run_blocks(blocks: list[str], workdir: Path, monkeypatch) -> dict:
    monkeypatch.chdir(workdir)
    namespace: dict = {"__name__": "training_page"}
    checked = 0
    for number, block in enumerate(blocks, 1):
        exec(compile(block, f"{PAGE} (python block {number})", "exec"), namespace)
        checked += check_shapes(block, namespace, number)
    assert checked >= 4, "the page's shape comments were not found"
    return namespace


def check_shapes(block: str, namespace: dict, number: int) -> int:
    """Every ``expression  # dtype [shape]`` line of ``block``, against the value left in
    ``namespace`` (an assignment's target, or the expression); how many there were."""
    checked = 0
    for line in block.splitlines():
        found = SHAPED.match(line)
        if found is None:
            continue
        code, dtype, dims = found.groups()
        target = code.split(" = ", 1)[0] if " = " in code else code
        value = eval(target, namespace)
        shape = tuple(int(d) for d in dims.split(","))
        where = f"block {number}: {code.strip()}"
        assert str(value.dtype).removeprefix("torch.") == dtype, where
        assert tuple(value.shape[1:]) == shape[1:] and 0 < value.shape[0] <= shape[0], (where, value.shape)
        checked += 1
    return checked


def test_the_readme_makes_what_the_page_reads(workdir):
    from expressive_mocap.dataset import load_dataset

    ds = load_dataset(workdir / training_command()[training_command().index("-o") + 1])
    assert len(ds) == 2 * len(CLIPS) and {"positions", "heading", "rotations"} <= set(ds.kinds)
    names = [n for n in ds.names if not n.endswith("@mirrored")]
    assert names == sorted(CLIPS)


def test_the_pages_numpy_code_runs_on_the_readmes_dataset(workdir, monkeypatch):
    blocks = [b for b in python_blocks() if "torch" not in b]
    assert len(blocks) >= 2
    namespace = run_blocks(blocks, workdir, monkeypatch)
    train, ds = namespace["train"], namespace["ds"]
    assert train.next_epoch == 10  # ten epochs ran
    batch = namespace["batch"]
    train_clips = {ds.names[c] for c in namespace["parts"]["train"]}
    assert {ds.names[c].removesuffix("@mirrored") for c in batch["clip"]} <= train_clips  # the split's only
    assert not any(name.endswith("@mirrored") for name in train_clips)
    assert batch["mirrored"].any() and batch["dropped"].any()  # the page's augmentation drew


@pytest.mark.torch
def test_the_pages_torch_code_runs_on_the_readmes_dataset(workdir, monkeypatch):
    pytest.importorskip("torch")
    blocks = python_blocks()
    assert any("torch" in b for b in blocks)
    namespace = run_blocks(blocks, workdir, monkeypatch)
    assert namespace["train"].epoch == 9
