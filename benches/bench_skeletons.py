#!/usr/bin/env python
"""Any skeleton: joint maps and round trips on every Bandai-Namco clip and the non-Bandai files,
the speed of retargeting, and mixed-skeleton preprocessing against the one-skeleton path.

    python benches/bench_skeletons.py [--data DIR] [--other DIR] [--clips N] [--rounds R]

1. **Maps and round trips.** Every clip of both Bandai-Namco datasets and every file of the
   non-Bandai folder (CMU, Xia-style) is mapped with no map file; each is retargeted onto another
   skeleton (Bandai clips onto the CMU file's, the others onto a Bandai clip's) and back, without
   planting the feet, and the largest angle between a mapped bone's direction before and after
   is reported (bones: upper and lower legs, feet, clavicles, upper arms, forearms, neck).
2. **Retargeting a 1,000-frame clip**: the CMU file's first 1,000 frames onto the Bandai
   skeleton and a 1,000-frame Bandai walk onto the CMU skeleton, with and without planted feet,
   with the Rust kernels and with the NumPy twins (FK, the pose transfer, contacts, leg IK and
   planting are kernels; the rest is NumPy either way). Median of 15 calls after a warm-up; the
   Rust output's world positions are first checked within 1e-6 (file units) of the twins'.
3. **Mixed preprocessing.** ``--clips`` dataset-2 clips (every k-th, sorted) preprocessed as
   they are (one skeleton, the default path), and the same clips with every second one
   retargeted onto the CMU skeleton beforehand (a mixed archive) with ``--canonical``, which puts
   those back onto the canonical body; each run a fresh process, the two alternated ``--rounds``
   times. Speed in frames a second of input; every run must have written every clip.

Every check raises (benches/harness.py) before a figure is written: a clip with no joint map, a
retarget whose two backends disagree, a preprocessing run that lost a clip.

Data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022), CC BY-NC
4.0; the CMU Graphics Lab Motion Capture Database (subject 131, via bvh11, MIT); deep-motion-
editing's demo files (BSD-2). The repository holds none of them.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.backend import use_backend
from expressive_mocap.body import find_joint_map
from expressive_mocap.skeletons import retarget
from harness import Stopwatch, check_close, check_equal, log, median, repeat
from results import write_section  # benches/results.py: this script rewrites only its own section

REPO = Path(__file__).resolve().parent.parent
TITLE = "Any skeleton: maps, round trips, retargeting, mixed archives"
CACHE = Path.home() / ".cache" / "motion-data" / "dataset"
_LIMB = [("upper_leg", "lower_leg"), ("lower_leg", "foot"), ("clavicle", "upper_arm"), ("upper_arm", "forearm")]
BONES = [(f"{s}_{a}", f"{s}_{b}") for s in ("left", "right") for a, b in _LIMB] + [("neck", "head")]
POSITION_TOL = 1e-6  # file units: Rust against the NumPy twins (planted feet: 4e-8 cm measured)


def directions(motion: em.Motion) -> np.ndarray:
    jmap = find_joint_map(motion.skeleton)
    p = motion.positions()
    v = np.stack([p[:, jmap[b]] - p[:, jmap[a]] for a, b in BONES], axis=1)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def worst_angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1, 1))).max())


def maps_and_round_trips(data: Path, other: Path) -> list[str]:
    cmu = em.read_bvh(other / "cmu_scaled_131_03.bvh")
    bandai = sorted((data / "Bandai-Namco-Research-Motiondataset-1" / "data").glob("*.bvh"))
    bandai += sorted((data / "Bandai-Namco-Research-Motiondataset-2" / "data").glob("*.bvh"))
    a_bandai = em.read_bvh(bandai[0])
    worst, mapped, frames, watch = 0.0, 0, 0, Stopwatch()
    for k, path in enumerate(bandai):
        motion = em.read_bvh(path)
        find_joint_map(motion.skeleton)  # raises if not found
        mapped += 1
        back = retarget(retarget(motion, cmu, plant_feet=False), motion, plant_feet=False)
        worst = max(worst, worst_angle(directions(back), directions(motion)))
        frames += motion.n_frames
        if k % 500 == 0:
            log(f"  {k}/{len(bandai)} clips, worst so far {worst:.2g} degrees")
    seconds = watch.elapsed()
    lines = [
        f"- Bandai-Namco clips mapped with no map file: {mapped} of {len(bandai)} (both datasets); round trip "
        f"onto the CMU skeleton and back, largest mapped-bone error **{worst:.2g} degrees** "
        f"({frames:,} frames, {seconds:.0f} s for both retargets, reading and checking)."
    ]
    for path in sorted(other.glob("*.bvh")):
        motion = em.read_bvh(path)
        jmap = find_joint_map(motion.skeleton)
        back = retarget(retarget(motion, a_bandai, plant_feet=False), motion, plant_feet=False)
        planted = retarget(retarget(motion, a_bandai), motion, plant_feet=False)
        lines.append(
            f"- {path.name}: {len(jmap.joints)} roles found ({sum(h != 'topology' for h in jmap.how.values())} by "
            f"name), {len(jmap.unmapped)} joints unmapped; round trip through a Bandai skeleton "
            f"{worst_angle(directions(back), directions(motion)):.2g} degrees, with planted feet on the way "
            f"{worst_angle(directions(planted), directions(motion)):.2g} degrees"
        )
    return lines


def timed(function, repeats: int = 15) -> float:
    """Milliseconds: the median of ``repeats`` calls after one warm-up."""
    return median(repeat(function, repeats, warmup=1)) * 1000


def same_retarget(source: em.Motion, target: em.Motion, plant: bool, what: str) -> None:
    """The Rust kernels' retarget has the twins' frames and world positions (within POSITION_TOL)."""
    out = {}
    for backend in ("rust", "numpy"):
        with use_backend(backend):
            out[backend] = retarget(source, target, plant_feet=plant)
    check_equal(out["rust"].n_frames, source.n_frames, f"{what}: frames")
    check_close(out["rust"].positions(), out["numpy"].positions(), f"{what}: world positions", atol=POSITION_TOL)


def retarget_speed(data: Path, other: Path) -> list[str]:
    cmu = em.read_bvh(other / "cmu_scaled_131_03.bvh")
    walks = sorted((data / "Bandai-Namco-Research-Motiondataset-2" / "data").glob("dataset-2_walk_normal_*.bvh"))
    clips = [em.read_bvh(p) for p in walks[:8]]
    walk = em.Motion(
        clips[0].skeleton,
        np.concatenate([c.rotations for c in clips])[:1000],
        np.concatenate([c.translations for c in clips])[:1000],
        clips[0].frame_time,
    )
    cases = {"CMU file (1,000 frames) onto the Bandai skeleton": (cmu[:1000], clips[0]),
             "Bandai walk (1,000 frames) onto the CMU skeleton": (walk, cmu)}  # fmt: skip
    lines = ["| clip | feet | Rust kernels (ms) | NumPy twins (ms) |", "|---|---|---|---|"]
    for name, (source, target) in cases.items():
        for plant in (True, False):
            same_retarget(source, target, plant, f"{name}, {'planted' if plant else 'as carried'}")
            row = []
            for backend in ("rust", "numpy"):
                with use_backend(backend):
                    row.append(timed(lambda s=source, t=target, p=plant: retarget(s, t, plant_feet=p)))
            lines.append(f"| {name} | {'planted' if plant else 'as carried'} | {row[0]:.1f} | {row[1]:.1f} |")
    return lines


_CHILD = """
import json, sys, time
from expressive_mocap.dataset import preprocess
start = time.perf_counter()
summary = preprocess(sys.argv[1], sys.argv[2], canonical=sys.argv[3] == "1", progress=False)
print(json.dumps({"seconds": time.perf_counter() - start, "ok": summary.clips_ok, "failed": summary.clips_failed}))
"""


def mixed_preprocessing(data: Path, other: Path, clips: int, rounds: int) -> list[str]:
    paths = sorted((data / "Bandai-Namco-Research-Motiondataset-2" / "data").glob("*.bvh"))
    paths = paths[:: max(1, len(paths) // clips)][:clips]
    cmu = em.read_bvh(other / "cmu_scaled_131_03.bvh")
    with tempfile.TemporaryDirectory() as tmp:
        one, mixed = Path(tmp, "one"), Path(tmp, "mixed")
        one.mkdir()
        mixed.mkdir()
        frames = 0
        for k, path in enumerate(paths):
            (one / path.name).symlink_to(path)
            if k % 2:
                # With six decimals, as the real CMU file (and the Bandai-Namco files) are written.
                em.write_bvh(retarget(em.read_bvh(path), cmu), mixed / path.name, decimals=6)
            else:
                (mixed / path.name).symlink_to(path)
            frames += em.read_bvh(path).n_frames
        runs: dict[str, list[float]] = {"one skeleton": [], "one skeleton, --canonical": [], "mixed, --canonical": []}
        sources = {
            "one skeleton": (one, "0"),
            "one skeleton, --canonical": (one, "1"),
            "mixed, --canonical": (mixed, "1"),
        }
        for r in range(rounds):
            for name, (src, canonical) in sources.items():
                out = Path(tmp, f"out{r}{len(runs[name])}{canonical}{src.name}")
                env = dict(os.environ, PYTHONPATH=str(Path(em.__file__).parent.parent))
                result = subprocess.run(
                    [sys.executable, "-c", _CHILD, str(src), str(out), canonical],
                    capture_output=True, text=True, check=True, env=env,
                )  # fmt: skip
                report = json.loads(result.stdout)
                check_equal((report["ok"], report["failed"]), (len(paths), 0), f"{name}: clips written, failed")
                runs[name].append(report["seconds"])
            log(f"  round {r + 1}: " + ", ".join(f"{k} {v[-1]:.2f} s" for k, v in runs.items()))
    base = median(runs["one skeleton"])
    lines = [
        f"{len(paths)} dataset-2 clips ({frames:,} frames); the mixed archive has every second clip on the CMU "
        f"skeleton (31 joints, metres, 3-channel ZYX joints). Median of {rounds} fresh processes each:",
        "",
        "| archive | seconds | frames/s | speed against the one-skeleton path |",
        "|---|---|---|---|",
    ]
    for name, seconds in runs.items():
        middle = median(seconds)
        lines.append(f"| {name} | {middle:.2f} | {frames / middle:,.0f} | {base / middle:.2f}x |")
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--data", type=Path, default=CACHE, help="folder holding Bandai-Namco-Research-Motiondataset-1/2"
    )
    parser.add_argument("--other", type=Path, default=REPO.parent / "shared" / "data" / "other")
    parser.add_argument("--clips", type=int, default=600, help="dataset-2 clips in the preprocessing comparison")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--out", type=Path, help="write the section to this file instead of benches/RESULTS.md")
    args = parser.parse_args()
    log("maps and round trips on every clip ...")
    maps = maps_and_round_trips(args.data, args.other)
    log("retargeting speed ...")
    speed = retarget_speed(args.data, args.other)
    log("mixed preprocessing ...")
    mixed = mixed_preprocessing(args.data, args.other, args.clips, args.rounds)
    cpu = platform.processor() or platform.machine()
    text = "\n".join(
        [
            f"`python benches/bench_skeletons.py --clips {args.clips} --rounds {args.rounds}` on "
            f"{datetime.date.today()}, {os.cpu_count()} cores ({cpu}), Python {platform.python_version()}.",
            "",
            "### Maps and round trips (no map file, feet not planted unless said)",
            "",
            *maps,
            "",
            "### Retargeting a 1,000-frame clip",
            "",
            *speed,
            "",
            "### Mixed-skeleton preprocessing",
            "",
            *mixed,
            "",
            "Data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0; "
            "CMU Graphics Lab Motion Capture Database (via bvh11); deep-motion-editing demo files (BSD-2).",
        ]
    )
    kwargs = {"path": args.out} if args.out else {}
    print(write_section(TITLE, text, **kwargs))


if __name__ == "__main__":
    main()
