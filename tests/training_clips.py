"""A small dataset for the training-side tests: six real dataset-2 clips (one in a subfolder),
preprocessed with positions, rotations and contacts (Bandai-Namco-Research-Motiondataset,
CC BY-NC 4.0)."""

from __future__ import annotations

import os
from pathlib import Path

from expressive_mocap.dataset import preprocess

CLIPS = [
    "dataset-2_walk_normal_001",
    "dataset-2_walk_normal_002",
    "dataset-2_walk_elderly_001",
    "dataset-2_run_normal_001",
    "dataset-2_run_elderly_002",
    "sub/dataset-2_walk-turn-left_active_002",
]


def training_dataset(bandai2_dir: Path, root: Path) -> Path:
    """Preprocess :data:`CLIPS` from ``bandai2_dir`` into ``root / "ds"``; its path."""
    (root / "src" / "sub").mkdir(parents=True)
    for name in CLIPS:
        os.symlink(bandai2_dir / f"{name.rsplit('/', 1)[-1]}.bvh", root / "src" / f"{name}.bvh")
    summary = preprocess(root / "src", root / "ds", keep="positions,rotations,contacts", progress=False)
    assert summary.clips_ok == len(CLIPS)
    return root / "ds"
