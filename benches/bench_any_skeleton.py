"""What applying a model to another skeleton costs: python benches/bench_any_skeleton.py

The same real walk (dataset-2 `walk_normal_002`, 1,000 frames taken from the walk repeated) on
its own Bandai-Namco skeleton and retargeted onto the CMU file's skeleton (31 joints) and a
Xia-style file's (31 joints), then, in one run, rounds alternating:
- `modulate` with the shipped body model (decompose and recompose at 0.5), in Python, as the
  command does it: on the model's skeleton directly, or through the canonical body
  (``Carried``: retarget onto it, the model, the edit carried back);
- `exaggerate` to 3 with a model ranked on dataset-2's walks, foot locking on.
Medians of the rounds; Rust kernels. Each edit's output is checked first (benches/harness.py; a
failed check raises): the input's joints and frames (exaggeration retimes: some frames), finite
values, unit rotations. Writes the section "Models on other skeletons" of benches/RESULTS.md
(``--out``: another file).
Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database (via bvh11); deep-motion-editing demo files (BSD-2).
"""

from __future__ import annotations

import argparse
import platform
import time
import warnings
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling import BodyModel, decompose
from expressive_mocap.exaggeration import exaggerate, train
from expressive_mocap.skeletons import retarget
from expressive_mocap.skeletons.canonical import carried_for
from harness import check, check_close, check_equal, median, timed
from results import RESULTS, write_section

HERE = Path(__file__).resolve().parent
FRAMES = 1000


def walk_of(d2: Path) -> em.Motion:
    walk = em.read_bvh(d2 / "dataset-2_walk_normal_002.bvh")
    repeats = -(-FRAMES // walk.n_frames)
    rotations = np.concatenate([walk.rotations] * repeats)[:FRAMES]
    translations = np.concatenate([walk.translations] * repeats)[:FRAMES]
    return em.Motion(walk.skeleton, rotations, translations, walk.frame_time)


def through(model, motion: em.Motion, edit):
    """``edit`` of ``motion`` by ``model`` as the commands apply it: on the model's skeleton, or
    through its body and back."""
    carried = carried_for(motion, model)
    if carried is None:
        return edit(motion)
    return carried.back(edit(carried.body))


def check_edit(edited: em.Motion, motion: em.Motion, what: str, retimed: bool) -> None:
    """An edit of ``motion``: its joints, its frames (some frames when the edit changes the timing),
    finite values, unit rotations."""
    check_equal(edited.skeleton.names, motion.skeleton.names, f"{what}: joints")
    if retimed:
        check(edited.n_frames > 0, f"{what}: no frames")
    else:
        check_equal(edited.n_frames, motion.n_frames, f"{what}: frames")
    check(np.isfinite(edited.translations).all(), f"{what}: translations not finite")
    norms = np.linalg.norm(edited.rotations, axis=-1)
    check_close(norms, np.ones_like(norms), f"{what}: rotation norms", atol=1e-9)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path.home() / ".cache" / "motion-data" / "dataset"))
    parser.add_argument("--other", default=str(HERE.parent.parent / "shared" / "data" / "other"))
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--out", type=Path, default=RESULTS, help="write the section into this file")
    args = parser.parse_args()
    warnings.simplefilter("ignore")  # estimates outside the trained range: not what is timed
    d2, other = Path(args.data) / "Bandai-Namco-Research-Motiondataset-2" / "data", Path(args.other)
    own = walk_of(d2)
    motions = {
        "own (Bandai-Namco, 22 joints)": own,
        "CMU skeleton (31 joints)": retarget(own, em.read_bvh(other / "cmu_scaled_131_03.bvh"), fps=own.fps),
        "Xia-style skeleton (31 joints)": retarget(own, em.read_bvh(other / "dme_rest.bvh"), fps=own.fps),
    }
    body_model = BodyModel.load()
    people = [
        [em.read_bvh(d2 / f"dataset-2_walk_{s}_{p:03d}.bvh") for s in ("exhausted", "normal", "active")]
        for p in range(1, 9)
    ]
    walks_model = train(people, [1, 2, 3])
    jobs = {
        "modulate (shipped body model)": (body_model, lambda m: decompose(m, body_model).recompose(0.5)),
        "exaggerate to 3 (walks model, feet locked)": (walks_model, lambda m: exaggerate(walks_model, m, 3.0)[0]),
    }
    times: dict = {(job, name): [] for job in jobs for name in motions}
    with em.use_backend("rust"):
        for job, (model, edit) in jobs.items():
            for name, motion in motions.items():
                # Also the warm-up (plans, caches). Exaggeration changes the timing too: other frame counts.
                check_edit(through(model, motion, edit), motion, f"{job}, {name}", job.startswith("exaggerate"))
        for _ in range(args.rounds):
            for job, (model, edit) in jobs.items():
                for name, motion in motions.items():
                    times[job, name].append(timed(through, model, motion, edit)[0])
    lines = [
        f"`python benches/bench_any_skeleton.py --rounds {args.rounds}` on {time.strftime('%Y-%m-%d')}, "
        f"{platform.machine()}, Python {platform.python_version()}, Rust kernels; median of {args.rounds} "
        f"rounds, alternating. A {FRAMES}-frame real walk (dataset-2 `walk_normal_002` repeated) on its own "
        "skeleton and retargeted onto two others; on another skeleton the edit goes through the model's body "
        "and back (retargeting there, carrying the edit back).",
        "",
        "| edit | skeleton | ms | against its own skeleton |",
        "|---|---|---|---|",
    ]
    for job in jobs:
        base = median(times[job, next(iter(motions))])
        for name in motions:
            t = median(times[job, name])
            lines.append(f"| {job} | {name} | {1000 * t:.1f} | {t / base:.2f}x |")
    lines += [
        "",
        "Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0); CMU (via bvh11); deep-motion-editing (BSD-2).",
    ]
    text = "\n".join(lines)
    print(text)
    write_section("Models on other skeletons", text, args.out)


if __name__ == "__main__":
    main()
