"""Small archives that mix skeletons and frame rates, for the preprocess tests: short dataset-2
clips (30 fps; Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0) and the CMU clips beside the
archives (120 fps; CMU Graphics Lab Motion Capture Database). Their fixture, ``mixed_zip``, is in
tests/conftest.py."""

from __future__ import annotations

import zipfile
from pathlib import Path

from expressive_mocap.bvh import read_header

BANDAI = ("raise-up-both-hands_active_022", "raise-up-both-hands_active_025", "wave-left-hand_active_011")
CMU = ("cmu_01_01", "cmu_scaled_131_03")


def zip_of(path: Path, members: dict[str, Path]) -> Path:
    """A deflated zip at ``path`` holding each source file under its member name."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for name, source in members.items():
            archive.write(source, name)
    return path


def bandai_members(bandai2_dir: Path, count: int = len(BANDAI)) -> dict[str, Path]:
    return {f"dataset-2_{clip}.bvh": bandai2_dir / f"dataset-2_{clip}.bvh" for clip in BANDAI[:count]}


def cmu_members(other_dir: Path) -> dict[str, Path]:
    return {f"{clip}.bvh": other_dir / f"{clip}.bvh" for clip in CMU}


def source_rates(members: dict[str, Path]) -> dict[str, tuple[int, float]]:
    """Each clip's (frames, frame rate) as its own file's header says."""
    out = {}
    for name, path in members.items():
        header = read_header(path)[0]
        out[name[:-4]] = (header.frames, 1.0 / header.frame_time)
    return out
