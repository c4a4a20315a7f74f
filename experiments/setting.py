"""What the experiments on other rigs share: their command line (``--other``, ``--data``), the
unpacked Bandai-Namco data, the walks model they exaggerate with, and running a command as a
user would, its report kept off the screen.

    from setting import arguments, bandai_dir, run, walks_model
"""

from __future__ import annotations

import argparse
import contextlib
import os
import subprocess
from pathlib import Path

import expressive_mocap as em
from expressive_mocap.cli import main as cli
from expressive_mocap.exaggeration import train
from expressive_mocap.skeletons import synthetic_walk

REPO = Path(__file__).resolve().parent.parent

__all__ = ["REAL", "REPO", "SYNTHETIC", "arguments", "bandai_dir", "described", "rig_targets", "run", "walks_model"]

SYNTHETIC = ("cmu", "mixamo", "game", "smpl", "lafan")  # the package's synthetic rigs
REAL = ("m21_walk", "cmu_01_01", "cmu_scaled_131_03")  # the shared folder's skeletons (dme_* is cmu_01_01's)


def arguments(doc: str) -> argparse.Namespace:
    """``--other`` (the shared folder of files on other rigs) and ``--data`` (where the
    Bandai-Namco archives are unpacked), under the first line of ``doc``."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--other", type=Path, default=REPO.parent / "shared" / "data" / "other")
    parser.add_argument("--data", type=Path, default=Path.home() / ".cache" / "motion-data")
    return parser.parse_args()


def described(doc: str) -> str:
    """What a script measures, for its write-up: its docstring's third paragraph on, up to its
    "Data:" paragraph, as one line (the first two are its title and its command line)."""
    return doc.split("\n\n", 2)[2].rsplit("\n\nData:", 1)[0].replace("\n", " ")


def bandai_dir(data: Path, number: int = 2) -> Path:
    """The clips of Bandai-Namco dataset ``number``, unpacked into ``data`` once."""
    unpack = [str(REPO.parent / "shared" / "data" / "unpack"), str(data)]
    found = subprocess.run(unpack, capture_output=True, text=True, check=True)
    return Path(found.stdout.strip().splitlines()[-1]) / f"Bandai-Namco-Research-Motiondataset-{number}" / "data"


def walks_model(dataset: Path):
    """An exaggeration model of dataset-2's walks: takes 1-8 of exhausted, normal and active as 8
    people at intensities 1-3 (the held-out takes are 9 on)."""
    styles = ("exhausted", "normal", "active")
    people = [[em.read_bvh(dataset / f"dataset-2_walk_{s}_{p:03d}.bvh") for s in styles] for p in range(1, 9)]
    return train(people, (1.0, 2.0, 3.0))


def rig_targets(other: Path, work: Path) -> dict[str, Path]:
    """Rig name -> a BVH file of it to retarget onto (``retarget --to``): each synthetic rig's walk,
    written into ``work``, and the walks of :data:`REAL` in ``other``."""
    targets = {}
    for rig in SYNTHETIC:
        targets[rig] = work / f"{rig}.bvh"
        em.write_bvh(synthetic_walk(rig).motion, targets[rig])
    return targets | {name: other / f"{name}.bvh" for name in REAL}


def run(*args) -> None:
    """``expressive-mocap ARGS`` in this process, its report and warnings kept off the screen."""
    with open(os.devnull, "w") as quiet, contextlib.redirect_stdout(quiet), contextlib.redirect_stderr(quiet):
        code = cli([*map(str, args)])
    if code != 0:
        raise SystemExit(f"expressive-mocap {' '.join(map(str, args))} failed")
