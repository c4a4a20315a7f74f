"""What fitting joint positions costs: python benches/bench_fit.py

A real walk (dataset-2 `walk_normal_002`, 1,000 frames taken from the walk repeated) put into the
`humanml3d` and `h36m17` layouts (the package's forward kinematics, each layout joint its role's
joint), then in rounds alternating: the fit onto the layout's own skeleton alone
(``fit_layout``), and the whole ``fit_positions`` onto the Bandai-Namco skeleton and onto the CMU
file's (31 joints), clean and with 1 cm of Gaussian noise (which adds the denoising, the steadied
feet and a second fit). Medians of the rounds; Rust kernels. Each result is checked first
(benches/harness.py; a failed check raises): the target's joints, every frame, the clean fit
within 1 cm of the positions on the walk's own skeleton. Writes the section "Fitting joint
positions" of benches/RESULTS.md (``--out``: another file).
Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database (via bvh11).
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.skeletons.fit import fit_positions
from expressive_mocap.skeletons.layout_fit import fit_layout
from expressive_mocap.skeletons.layouts import LAYOUTS
from harness import check, check_equal, median, timed
from results import RESULTS, write_section

HERE = Path(__file__).resolve().parent
FRAMES = 1000


def walk_of(d2: Path) -> em.Motion:
    walk = em.read_bvh(d2 / "dataset-2_walk_normal_002.bvh")
    repeats = -(-FRAMES // walk.n_frames)
    rotations = np.concatenate([walk.rotations] * repeats)[:FRAMES]
    translations = np.concatenate([walk.translations] * repeats)[:FRAMES]
    return em.Motion(walk.skeleton, rotations, translations, walk.frame_time)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path.home() / ".cache" / "motion-data" / "dataset"))
    parser.add_argument("--other", default=str(HERE.parent.parent / "shared" / "data" / "other"))
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--out", type=Path, default=RESULTS, help="write the section into this file")
    args = parser.parse_args()
    sys.path.insert(0, str(HERE.parent / "tests" / "skeletons"))
    from test_fit_positions import to_layout  # the tests' way of putting a capture into a layout

    d2 = Path(args.data) / "Bandai-Namco-Research-Motiondataset-2" / "data"
    walk = walk_of(d2)
    targets = {"Bandai-Namco (22 joints)": walk, "CMU (31 joints)": em.read_bvh(Path(args.other) / "cmu_01_01.bvh")}
    noise = np.random.default_rng(0)
    jobs = {}
    for layout in ("humanml3d", "h36m17"):
        clean = to_layout(walk, layout)
        noisy = clean + noise.normal(0.0, 1.0, clean.shape)
        jobs[layout, "fit_layout (own skeleton)", "clean"] = (fit_layout, (clean, LAYOUTS[layout], walk.fps), {})
        for name, target in targets.items():
            for kind, positions in (("clean", clean), ("1 cm noise", noisy)):
                jobs[layout, f"fit_positions onto {name}", kind] = (
                    fit_positions,
                    (positions, layout, target),
                    {"fps": walk.fps},
                )
    times: dict = {job: [] for job in jobs}
    with em.use_backend("rust"):
        for job, (fn, call, kwargs) in jobs.items():  # also the warm-up
            result = fn(*call, **kwargs)
            if fn is fit_layout:
                check_equal(result.n_frames, FRAMES, f"{job}: frames")
                continue
            out, report = result
            target = targets[job[1].split(" onto ")[1]]
            check_equal(out.skeleton.names, target.skeleton.names, f"{job}: joints")
            check_equal(out.n_frames, FRAMES, f"{job}: frames")
            if target is walk and job[2] == "clean":
                check(report.mean_all < 1.0, f"{job}: fit error {report.mean_all:.2f} cm")
        for _ in range(args.rounds):
            for job, (fn, call, kwargs) in jobs.items():
                times[job].append(timed(fn, *call, **kwargs)[0])
    lines = [
        f"`python benches/bench_fit.py --rounds {args.rounds}` on {time.strftime('%Y-%m-%d')}, "
        f"{platform.machine()}, Python {platform.python_version()}, Rust kernels; median of {args.rounds} "
        f"rounds, alternating. A {FRAMES}-frame real walk (dataset-2 `walk_normal_002` repeated) as joint "
        "positions in a layout, fitted; `fit_positions` includes the retarget onto the target.",
        "",
        "| layout | what | positions | ms |",
        "|---|---|---|---|",
    ]
    for job in jobs:
        lines.append(f"| {job[0]} | {job[1]} | {job[2]} | {1000 * median(times[job]):.1f} |")
    lines += [
        "",
        "Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0); CMU Graphics Lab Motion Capture Database "
        "(via bvh11).",
    ]
    text = "\n".join(lines)
    print(text)
    write_section("Fitting joint positions", text, args.out)


if __name__ == "__main__":
    main()
