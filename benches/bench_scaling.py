#!/usr/bin/env python
"""How ``expressive-mocap preprocess`` scales with cores: whole processes, pinned.

    python benches/bench_scaling.py [--data DIR] [--rounds 5] [--cores 1,2,...] [--write-results]

Each run is the command line itself (``python -m expressive_mocap.cli preprocess DATA -o OUT``,
start-up, imports and exit included), in a fresh process pinned to the first N cores with
``sched_setaffinity`` before it starts (Rust's thread pool sizes itself from that set, and the
Python threads share it), with and without ``--model``; the package byte-compiled first, as pip
leaves it installed. Beside them, the Rust kernels alone (``read_bvh_many`` and
``forward_kinematics_many`` of every clip, timed inside a process pinned the same way): how far
this machine's cores take the parallel part at best. The core counts are alternated round after
round (their order rotated), and each configuration's median is compared with the 1-core median
of the same run: the speed-up ``t(1) / t(N)``, and the parallel efficiency ``speed-up / N``.
Before the figures are written, every run is checked to have written every clip with no failure
and the same frames. ``--cores`` defaults to 1, 2, 4, ... up to this machine's.

Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
The repository never contains it.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from harness import byte_compile, check, check_equal, clock, commit, cpu_name, log, median, memory_gib, rotated
from results import write_section

REPO = Path(__file__).resolve().parents[1]
DEFAULT_DATA = Path.home() / ".cache/motion-data/dataset/Bandai-Namco-Research-Motiondataset-2/data"
TITLE = "Scaling with cores: `benches/bench_scaling.py`"
TARGET_2_CORES = 1.85  # the whole process on 2 cores against 1


# The Rust kernels alone, in a process pinned as the runs are, timed inside it (imports and
# start-up not counted): what this machine's cores give the parallel part at best.
KERNELS = """
import sys, time
from pathlib import Path
import expressive_mocap as em
paths = sorted(Path(sys.argv[1]).glob("*.bvh"))
started = time.perf_counter()
motions = em.read_bvh_many(paths)
em.forward_kinematics_many(motions)
print(time.perf_counter() - started, len(motions), sum(m.n_frames for m in motions))
"""
KERNELS_RUN = "kernels alone"


def pinned(command: list[str], cores: int) -> tuple[float, str]:
    """``command`` in a fresh process pinned to the first ``cores`` cores (the package's bytecode
    read, its Rust backend): its wall seconds, measured here, and its output."""
    allowed = sorted(os.sched_getaffinity(0))[:cores]
    environment = {**os.environ, "PYTHONPATH": str(REPO / "python")}
    environment.pop("EXPRESSIVE_MOCAP_BACKEND", None)
    environment.pop("PYTHONDONTWRITEBYTECODE", None)
    started = clock()
    done = subprocess.run(
        command,
        env=environment,
        capture_output=True,
        text=True,
        preexec_fn=lambda: os.sched_setaffinity(0, allowed),
    )
    seconds = clock() - started
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command[:4])} ... on {cores} cores failed:\n{done.stderr}")
    return seconds, done.stdout


def kernels(data: Path, cores: int) -> dict:
    """The Rust kernels alone on ``cores`` cores: ``read_bvh_many`` and ``forward_kinematics_many``
    of every clip, timed inside the process."""
    _, output = pinned([sys.executable, "-c", KERNELS, str(data)], cores)
    seconds, clips, frames = output.split()
    return {"seconds": float(seconds), "clips": int(clips), "failed": 0, "frames": int(frames)}


def run(data: Path, out: Path, cores: int, model: bool) -> dict:
    """One preprocess command line pinned to ``cores`` cores: its wall seconds (measured here,
    around the whole process) and the dataset it wrote, checked."""
    shutil.rmtree(out, ignore_errors=True)
    command = [sys.executable, "-m", "expressive_mocap.cli", "preprocess", str(data), "-o", str(out)]
    seconds, _ = pinned(command + (["--model"] if model else []), cores)
    manifest = json.loads((out / "manifest.json").read_text())
    figures = {
        "seconds": seconds,
        "clips": len(manifest["clips"]),
        "failed": len(manifest.get("failures", [])),
        "frames": sum(clip["frames"] for clip in manifest["clips"]),
    }
    shutil.rmtree(out, ignore_errors=True)
    return figures


def core_counts(given: str | None) -> list[int]:
    available = len(os.sched_getaffinity(0))
    if given:
        counts = sorted({int(c) for c in given.split(",")})
        check(all(1 <= c <= available for c in counts), f"--cores {given}: this machine lets us use 1-{available}")
        return counts
    counts, c = [], 1
    while c <= available:
        counts.append(c)
        c *= 2
    return counts if counts[-1] == available else [*counts, available]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DEFAULT_DATA, help=f"folder of BVH files (default {DEFAULT_DATA})")
    parser.add_argument("--rounds", type=int, default=5, help="runs of each configuration (default 5)")
    parser.add_argument("--cores", help="comma-separated core counts (default 1, 2, 4, ... up to this machine's)")
    parser.add_argument("--no-model", action="store_true", help="skip the runs with --model")
    parser.add_argument("--write-results", action="store_true", help=f"rewrite the section {TITLE!r} of RESULTS.md")
    args = parser.parse_args()
    counts = core_counts(args.cores)
    clips = sorted(args.data.glob("*.bvh"))
    check(bool(clips), f"no .bvh files in {args.data}")
    for path in clips:  # warm the page cache: every run reads from memory
        path.read_bytes()
    byte_compile(REPO / "python" / "expressive_mocap")
    load, when, t0 = os.getloadavg(), datetime.datetime.now(), clock()
    names = ["default"] + ([] if args.no_model else ["--model"]) + [KERNELS_RUN]
    configs = [(cores, name) for name in names for cores in counts]
    runs: dict[tuple, list[dict]] = {config: [] for config in configs}
    work = Path(tempfile.mkdtemp(prefix="bench-scaling-"))
    try:
        for r in range(args.rounds):
            for cores, name in rotated(configs, r):
                if name == KERNELS_RUN:
                    figures = kernels(args.data, cores)
                else:
                    figures = run(args.data, work / "out", cores, name == "--model")
                log(f"round {r + 1}: {cores} cores, {name}: {figures['seconds']:.2f} s")
                runs[(cores, name)].append(figures)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    for config, figures in runs.items():
        for f in figures:
            check_equal((f["clips"], f["failed"]), (len(clips), 0), f"{config}: clips written and failed")
    check(len({f["frames"] for fs in runs.values() for f in fs}) == 1, "the runs wrote different frames")

    lines = [
        f"- date: {when:%Y-%m-%d %H:%M} (the run took {(clock() - t0) / 60:.1f} min)",
        f"- machine: {cpu_name()}, {os.cpu_count()} cores, {memory_gib():.1f} GiB RAM; Python "
        f"{sys.version.split()[0]}; commit {commit(REPO)}; load average at the start "
        f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}",
        f"- command: `python benches/bench_scaling.py --rounds {args.rounds}"
        f"{f' --cores {args.cores}' if args.cores else ''}`: `python -m expressive_mocap.cli preprocess DATA -o OUT"
        " [--model]`, whole processes pinned to the first N cores, medians; the kernels alone:"
        " `read_bvh_many` + `forward_kinematics_many` of every clip in a process pinned the same way,"
        " timed inside it (start-up and imports not counted)",
        f"- data: {len(clips)} clips, {sum(p.stat().st_size for p in clips) / 1e6:.1f} MB "
        "(Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0)",
        "",
        "| run | cores | wall s (median) | runs | speed-up over 1 core | efficiency |",
        "|---|---|---|---|---|---|",
    ]
    verdicts = []
    for name in names:
        one = median(f["seconds"] for f in runs[(counts[0], name)]) if counts[0] == 1 else None
        for cores in counts:
            seconds = median(f["seconds"] for f in runs[(cores, name)])
            speedup = one / seconds if one else float("nan")
            lines.append(
                f"| {name} | {cores} | {seconds:.2f} | {len(runs[(cores, name)])} | {speedup:.2f}x | "
                f"{speedup / cores:.0%} |"
            )
            if cores == 2 and one and name != KERNELS_RUN:
                verdict = "pass" if speedup >= TARGET_2_CORES else "FAIL"
                verdicts.append(f"{name}: 2 cores {speedup:.2f}x 1 core (target {TARGET_2_CORES}x): **{verdict}**")
    text = "\n".join([*lines, "", *(f"- {v}" for v in verdicts)]) + "\n"
    print(text)
    if args.write_results:
        write_section(TITLE, text, REPO / "benches" / "RESULTS.md")
        log(f"wrote the section {TITLE!r} of benches/RESULTS.md")


if __name__ == "__main__":
    main()
