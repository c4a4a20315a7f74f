#!/usr/bin/env python
"""Benchmark ``expressive-mocap preprocess`` on the whole Bandai-Namco dataset-2 archive.

    python benches/bench_preprocess.py [--data DIR] [--rounds R] [--limit N] [--no-numpy]
                                       [--out benches/RESULTS.md]

Each run is one call of ``preprocess`` (parse + FK + dynamic features + foot contacts + writing
the dataset; ``--model``: also the decomposition's activity) in a fresh child process, so its
peak memory (VmHWM) is its own. Configurations, alternated round by round (machines here drift
by +-30 %, so compare within a run):

- the unpacked folder, Rust kernels, 2 threads (the default);
- a .zip of the same files (made once in a temporary folder, deflated), read in place;
- the folder with the shipped body-mechanics model (keeps activity too), its network in float64
  (the default) and in float32 (``--model-float32``);
- the folder on 1 core (the child pinned with ``sched_setaffinity``: Rust's thread pool and the
  Python threads share that core), for the 1 -> 2 workers scaling;
- the folder on a Dask LocalCluster of 2 worker processes on loopback (``--dask``; the
  cluster's start-up is in the time; peak RSS is the client's only);
- the folder with the NumPy twins (``EXPRESSIVE_MOCAP_BACKEND=numpy``; one round, it is slow).

A section with the figures, the machine and the date is appended to ``--out``. Checked before it
is written (benches/harness.py; a failed check raises): every run read every clip with no failure
and wrote the same number of frames, and the kernels alone decoded, posed and measured every clip.

Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
The repository never contains it.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

from harness import Best, Stopwatch, check, check_equal, clock, commit, cpu_name, log, memory_gib, peak_rss, rotated
from results import write_section  # benches/results.py: this script rewrites only its own section

REPO = Path(__file__).resolve().parent.parent
TITLE = "Preprocessing the archive: `expressive-mocap preprocess`"  # its section of benches/RESULTS.md
DEFAULT_DATA = Path.home() / ".cache" / "motion-data" / "dataset" / "Bandai-Namco-Research-Motiondataset-2" / "data"
CITATION = (
    "Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), licensed CC BY-NC 4.0."
)
MB = 1e6

# name -> (source kind, environment, model: None, "float64" or "float32" network, cores: None = all)
CONFIGS = {
    "folder, Rust, 2 cores": ("folder", {}, None, None),
    "zip, Rust, 2 cores": ("zip", {}, None, None),
    "folder + --model, Rust, 2 cores": ("folder", {}, "float64", None),
    "folder + --model --model-float32, Rust, 2 cores": ("folder", {}, "float32", None),
    "folder, Rust, 1 core": ("folder", {}, None, 1),
    "folder, Dask LocalCluster (2 worker processes, loopback; start-up included)": (
        "folder",
        {"BENCH_CLUSTER": "local"},
        None,
        None,
    ),
    "folder, NumPy twins, 2 cores": ("folder", {"EXPRESSIVE_MOCAP_BACKEND": "numpy"}, None, None),
}


def child(src: str, out: str, model: str | None) -> None:
    """One preprocess run; prints one JSON line."""
    import expressive_mocap as em
    from expressive_mocap.dataset import preprocess

    with Stopwatch() as watch:
        summary = preprocess(
            src,
            out,
            model="" if model else None,
            model_float32=model == "float32",
            progress=False,
            cluster=os.environ.get("BENCH_CLUSTER"),
        )
    print(
        json.dumps(
            {
                "wall": watch.seconds,
                "headers": summary.headers_s,
                "kernels": summary.kernels_s,
                "write": summary.write_s,
                "clips": summary.clips_ok,
                "failed": summary.clips_failed,
                "frames": summary.frames,
                "bytes": summary.bytes_read,
                "peak": peak_rss(),
                "backend": em.get_backend(),
                "threads": getattr(em.backend._core, "num_threads", None),
            }
        )
    )


def kernels_child(folder: str) -> None:
    """The pipeline's kernel step alone (``clip_pipeline_many`` on every clip: reading the files,
    MOTION blocks, FK, features, contacts; headers prepared beforehand), and where its time goes:
    the same work split into the kernels it fuses (reading the files, parsing and decoding the
    MOTION blocks, FK, features and contacts), each timed on its own. Best of 3; one JSON line.
    Checked: every clip read, decoded, posed and measured, with its frames."""
    from expressive_mocap import ops
    from expressive_mocap.backend import kernels
    from expressive_mocap.body.contacts import FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD
    from expressive_mocap.dataset import format as fmt
    from expressive_mocap.dataset import sources, work

    items = sources.open_source(folder).items
    prepared = work.prepare(items, fmt.DEFAULT_KEEP, None)
    (group,) = prepared.groups  # dataset-2: one hierarchy
    core = kernels()
    best = Best()
    clips = len(group.clips)
    for _ in range(3):
        best.time("kernels", lambda: work.run_kernels(items, prepared, fmt.DEFAULT_KEEP, None, False))
        texts = best.time("read", lambda: [Path(clip.source).read_bytes() for clip in group.clips])
        check_equal(len(texts), clips, "kernels alone: files read")
        blocks = [ops.MotionBlock(text, clip.start, clip.frames, clip.layout) for text, clip in zip(texts, group.clips)]
        decoded = best.time("parse", lambda blocks=blocks: core.read_motion_blocks(blocks))
        check_equal(
            [len(r) for r, _ in decoded], [clip.frames for clip in group.clips], "kernels alone: frames decoded"
        )
        posed = best.time(
            "fk", lambda decoded=decoded: core.forward_kinematics_many([(r, t, group.parents) for r, t in decoded])
        )
        check_equal([len(p) for _, p in posed], [clip.frames for clip in group.clips], "kernels alone: frames posed")
        gait = [
            (world, local, clip.frame_time, clip.height, clip.hips_rest_height)
            for (_, world), (local, _), clip in zip(posed, decoded, group.clips)
        ]
        measured = best.time(
            "gait",
            lambda gait=gait: core.clip_gait_many(
                gait,
                group.gait_joints,
                HEIGHT_THRESHOLD,
                SPEED_THRESHOLD,
                MIN_DURATION,
                FLOOR_PERCENTILE,
                True,
                True,
                0.0,
            ),
        )
        check_equal(len(measured), clips, "kernels alone: clips measured")
    print(json.dumps(best))


def run_kernels_child(folder: Path, cores: int | None) -> dict:
    pin = (lambda: os.sched_setaffinity(0, set(sorted(os.sched_getaffinity(0))[:cores]))) if cores else None
    environment = {**os.environ, "PYTHONPATH": str(REPO / "python")}
    result = subprocess.run(
        [sys.executable, __file__, "--child-kernels", str(folder)],
        env=environment,
        capture_output=True,
        text=True,
        preexec_fn=pin,
    )
    if result.returncode != 0:
        raise SystemExit(f"kernel ceiling run failed:\n{result.stderr}")
    return json.loads(result.stdout.strip().splitlines()[-1])


def run_child(name: str, sources: dict, work: Path, clips: int) -> dict:
    """One configuration's run in a child process: its figures, checked to have read every one of
    the ``clips`` clips with no failure."""
    kind, env, model, cores = CONFIGS[name]
    out = work / "out"
    shutil.rmtree(out, ignore_errors=True)
    environment = {**os.environ, "PYTHONPATH": str(REPO / "python"), **env}
    command = [sys.executable, __file__, "--child", str(sources[kind]), "--child-out", str(out)] + (
        ["--child-model", model] if model else []
    )
    pin = (lambda: os.sched_setaffinity(0, set(sorted(os.sched_getaffinity(0))[:cores]))) if cores else None
    result = subprocess.run(command, env=environment, capture_output=True, text=True, preexec_fn=pin)
    if result.returncode != 0:
        raise SystemExit(f"{name}: the child failed:\n{result.stderr}")
    figures = json.loads(result.stdout.strip().splitlines()[-1])
    check_equal((figures["clips"], figures["failed"]), (clips, 0), f"{name}: clips written and failed")
    figures["out_bytes"] = sum(p.stat().st_size for p in out.iterdir())
    shutil.rmtree(out, ignore_errors=True)
    log(
        f"{name}: {figures['wall']:.2f} s (headers {figures['headers']:.2f}, kernels "
        f"{figures['kernels']:.2f}, write {figures['write']:.2f}), peak {figures['peak'] / MB:.0f} MB"
    )
    return figures


def machine() -> str:
    load = os.getloadavg()
    import numpy

    return (
        f"{cpu_name()}, {os.cpu_count()} cores, {memory_gib():.1f} GiB RAM; Python {platform.python_version()}, "
        f"NumPy {numpy.__version__}; commit {commit(REPO)}; load average at the start {load[0]:.1f}, "
        f"{load[1]:.1f}, {load[2]:.1f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--data", default=str(DEFAULT_DATA), help=f"folder of dataset-2 .bvh files (default {DEFAULT_DATA})"
    )
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the Rust configurations (default 3)")
    parser.add_argument(
        "--limit", type=int, help="only the first N clips (copied into a temporary folder; a quick run)"
    )
    parser.add_argument("--no-numpy", action="store_true", help="skip the NumPy-twin run")
    parser.add_argument(
        "--out",
        default=str(REPO / "benches" / "RESULTS.md"),
        help=f"markdown file whose section {TITLE!r} this rewrites (the others are kept)",
    )
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--child-kernels", help=argparse.SUPPRESS)
    parser.add_argument("--child-out", help=argparse.SUPPRESS)
    parser.add_argument("--child-model", choices=["float64", "float32"], help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child(args.child, args.child_out, args.child_model)
    if args.child_kernels:
        return kernels_child(args.child_kernels)

    started, t0 = datetime.datetime.now(), clock()
    info = machine()
    data = Path(args.data)
    paths = sorted(data.glob("*.bvh"))
    if not paths:
        raise SystemExit(f"no .bvh files in {data}")
    work = Path(tempfile.mkdtemp(prefix="bench-preprocess-"))
    try:
        folder = data
        if args.limit:
            paths = paths[: args.limit]
            folder = work / "clips"
            folder.mkdir()
            for p in paths:
                os.symlink(p, folder / p.name)
        size = sum(p.stat().st_size for p in paths)
        for p in paths:  # warm the page cache
            p.read_bytes()
        log(f"{len(paths)} clips, {size / MB:.1f} MB; making the zip ...")
        with Stopwatch() as zipping, zipfile.ZipFile(work / "clips.zip", "w", zipfile.ZIP_DEFLATED) as archive:
            for p in paths:
                archive.write(p, p.name)
        zip_seconds, zip_size = zipping.seconds, (work / "clips.zip").stat().st_size
        sources = {"folder": folder, "zip": work / "clips.zip"}

        runs: dict[str, list] = {name: [] for name in CONFIGS}
        rust = [n for n in CONFIGS if "NumPy" not in n]
        for r in range(args.rounds):
            for name in rotated(rust, r):  # rotate the order each round
                runs[name].append(run_child(name, sources, work, len(paths)))
        if not args.no_numpy:
            numpy_run = run_child("folder, NumPy twins, 2 cores", sources, work, len(paths))
            runs["folder, NumPy twins, 2 cores"].append(numpy_run)
        ceiling = {cores: run_kernels_child(folder, cores) for cores in (1, None)}
        log(f"kernels alone: {ceiling}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    frames = {r["frames"] for rs in runs.values() for r in rs}
    check(len(frames) == 1, f"the configurations wrote different numbers of frames: {sorted(frames)}")
    run = Run(
        limit=args.limit,
        rounds=args.rounds,
        info=info,
        started=started,
        seconds=clock() - t0,
        clips=len(paths),
        size=size,
        zip_size=zip_size,
        zip_seconds=zip_seconds,
        runs=runs,
        ceiling=ceiling,
    )
    text = report(run)
    print(text)
    write_section(TITLE, text, args.out)
    log(f"wrote the section {TITLE!r} of {args.out}")


@dataclass
class Run:
    """What one run measured, for :func:`report`: ``info`` the machine's line, ``seconds`` the
    whole run's, ``clips``, ``size`` (bytes), the zip's size and seconds, ``runs`` each
    configuration's child figures, ``ceiling`` the kernels alone on 1 core (key 1) and all (None)."""

    limit: int | None
    rounds: int
    info: str
    started: datetime.datetime
    seconds: float
    clips: int
    size: int
    zip_size: int
    zip_seconds: float
    runs: dict[str, list[dict]]
    ceiling: dict

    @property
    def frames(self) -> int:
        return next(r["frames"] for rs in self.runs.values() for r in rs)

    def med(self, name: str, key: str) -> float:
        return statistics.median(r[key] for r in self.runs[name])


def report(run: Run) -> str:
    """The section of benches/RESULTS.md: the setting, one row per configuration, the targets and
    the scaling ceiling."""
    return "\n".join(header(run) + table(run) + targets(run) + ceiling(run)) + "\n"


def header(run: Run) -> list[str]:
    return [
        f"- date: {run.started:%Y-%m-%d %H:%M} (the run took {run.seconds / 60:.1f} min)",
        f"- machine: {run.info}",
        f"- command: `python benches/bench_preprocess.py{' --limit ' + str(run.limit) if run.limit else ''}`; "
        f"{run.rounds} rounds of the Rust configurations, order rotated each round, each run a fresh child "
        "process (times: medians)",
        f"- load average at the end: {', '.join(f'{x:.1f}' for x in os.getloadavg())} "
        "(other jobs on the machine slow every figure alike)",
        f"- data: {run.clips} clips, {run.size / MB:.1f} MB, {run.frames:,} frames; the zip: "
        f"{run.zip_size / MB:.1f} MB deflated, made in {run.zip_seconds:.1f} s (not timed below)",
        "- each run: parse + FK + dynamic features + foot contacts (+ the decomposition with --model) + "
        "writing the dataset (positions, features, contacts[, activity]) to a local folder; page cache warm",
        f"- {CITATION}",
    ]


def table(run: Run) -> list[str]:
    lines = [
        "",
        "| configuration | runs | wall s | MB/s | frames/s | headers s | kernels s | writing s | peak RSS | output |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, rs in run.runs.items():
        if not rs:
            continue
        wall = run.med(name, "wall")
        lines.append(
            f"| {name} | {len(rs)} | {wall:.2f} | {run.size / MB / wall:.0f} | {run.frames / wall / 1e3:.0f} "
            f"k | {run.med(name, 'headers'):.2f} | {run.med(name, 'kernels'):.2f} | {run.med(name, 'write'):.2f} "
            f"| {max(r['peak'] for r in rs) / MB:.0f} MB | {rs[0]['out_bytes'] / MB:.0f} MB |"
        )
    return lines


def targets(run: Run) -> list[str]:
    folder = run.med("folder, Rust, 2 cores", "wall")
    found = [("folder < 3 s", folder < 3, f"{folder:.2f} s")]
    for goal, name in (
        ("zip < 5 s", "zip, Rust, 2 cores"),
        ("with --model < 5 s", "folder + --model, Rust, 2 cores"),
        ("... with --model --model-float32", "folder + --model --model-float32, Rust, 2 cores"),
    ):
        wall = run.med(name, "wall")
        found.append((goal, wall < 5, f"{wall:.2f} s"))
    if run.runs["folder, NumPy twins, 2 cores"]:
        ratio = run.runs["folder, NumPy twins, 2 cores"][0]["wall"] / folder
        found.append((">= 10x the NumPy path", ratio >= 10, f"{ratio:.1f}x"))
    peak = max(r["peak"] for rs in run.runs.values() for r in rs)
    found.append(("peak memory < 2 GB", peak < 2e9, f"{peak / MB:.0f} MB (largest of all runs)"))
    one = run.med("folder, Rust, 1 core", "wall")
    found.append(
        (
            "near-linear 1 -> 2 workers (>= 1.7x)",
            one / folder >= 1.7,
            f"{one / folder:.2f}x faster on 2 cores than on 1 ({one:.2f} s -> {folder:.2f} s)",
        )
    )
    lines = ["", "| target | measured | result |", "|---|---|---|"]
    return lines + [f"| {goal} | {shown} | {'**pass**' if ok else '**FAIL**'} |" for goal, ok, shown in found]


def ceiling(run: Run) -> list[str]:
    one_core, all_cores = run.ceiling[1], run.ceiling[None]
    parts = ", ".join(
        f"{label} {one_core[key]:.2f} s -> {all_cores[key]:.2f} s"
        for key, label in (
            ("read", "reading the files"),
            ("parse", "parsing and decoding the MOTION blocks"),
            ("fk", "FK"),
            ("gait", "features and contacts"),
        )
    )
    return [
        "",
        "The scaling ceiling on this machine, same run: the pipeline's kernel step alone "
        "(`clip_pipeline_many` on every clip, headers read beforehand; best of 3), 1 core -> 2 cores: "
        f"{one_core['kernels']:.2f} s -> {all_cores['kernels']:.2f} s "
        f"({one_core['kernels'] / all_cores['kernels']:.2f}x). Where its time goes (the kernels it fuses, each "
        f"called on its own on every clip, their intermediates kept between calls; 1 core -> 2 cores): {parts}.",
    ]


if __name__ == "__main__":
    main()
