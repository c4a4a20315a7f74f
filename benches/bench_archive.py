#!/usr/bin/env python
"""Benchmark expressive-mocap on the whole Bandai-Namco dataset-2 archive (2,902 BVH clips).

    python benches/bench_archive.py [--data DIR] [--peers pybvh,pymotion,bvhio] [--limit N]
                                    [--rounds R] [--out benches/RESULTS.md]

Measures, in one run (machines here drift by +-30 %, so only ratios taken in the same run count):

1. read (parse + Euler->quaternion, every clip into memory): page-cache floor, Rust
   ``read_bvh_many``, a Rust per-file ``read_bvh`` loop, and the NumPy twin backend;
2. FK of every frame of every clip, Rust vs NumPy twin, on the same loaded motions;
3. peers (upc-pymotion, bvhio, pybvh; ``pip install -r benches/requirements.txt``), with a
   spot check of their world positions against ours;
4. end-to-end (read + FK) ratios and peak RSS, each in its own child process;
5. a table on stdout and its own section of ``benches/RESULTS.md`` (the others kept), with the
   targets marked pass / fail.

Checked before any time is reported (benches/harness.py; a failed check raises): every clip read,
the per-file loop equal to ``read_bvh_many``, the NumPy twin's rotations within 1e-12 and
translations within 1e-9 of Rust's, FK positions of every backend and API within 1e-9 (file units)
and rotations within 1e-12 of Rust's ``m.fk()``, the SciPy reference's positions within 1e-9 on the
spot-check clips, and every child run of ours holding every joint-frame.

Data: Bandai-Namco-Research-Motiondataset (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
The repository never contains it (see docs/data.md): ``--data DIR``, else the ``unpack``
script of ``../shared/data`` next to the checkout.
"""

from __future__ import annotations

import argparse
import cProfile
import datetime
import gc
import io
import json
import os
import platform
import pstats
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

import expressive_mocap as em
from harness import (
    check,
    check_close,
    check_equal,
    clock,
    commit,
    cpu_name,
    log,
    median,
    memory_gib,
    peak_rss,
    ratio_median,
    rotated,
    timed,
)
from results import write_section  # benches/results.py: this script rewrites only its own section

REPO = Path(__file__).resolve().parent.parent
TITLE = "Whole archive: reading and forward kinematics"  # its section of benches/RESULTS.md
DATASET2 = Path("Bandai-Namco-Research-Motiondataset-2") / "data"
CITATION = (
    "Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022; "
    'Kobayashi et al., "Motion Capture Dataset for Practical Use of AI-based Motion Editing and '
    'Stylization", arXiv:2306.08861), licensed CC BY-NC 4.0.'
)
PEERS = ("pymotion", "bvhio", "pybvh")
PEER_LABEL = {"pymotion": "upc-pymotion 0.3.4", "bvhio": "bvhio 1.5.4", "pybvh": "pybvh 0.9.0"}
MB = 1e6
# Rust against the NumPy twin and the SciPy reference (file units: cm): measured 4.4e-16 on the
# rotations, 0 on the translations and 1.7e-13 on the FK positions over the whole archive.
ROTATION_TOL, POSITION_TOL = 1e-12, 1e-9


def progress(items, desc: str):
    # Same thin wrapper around every per-file loop (ours and peers), so its cost is shared.
    return tqdm(items, desc=desc, leave=False, mininterval=0.5, file=sys.stderr, dynamic_ncols=True)


# ----------------------------------------------------------------------------- data, machine


def find_data(folder: str | None) -> Path:
    """The folder of dataset-2 .bvh files: --data (that folder, or the unpack root), else unpack."""
    if folder is None:
        unpack = REPO.parent / "shared" / "data" / "unpack"
        out = subprocess.run(
            [str(unpack), str(Path.home() / ".cache" / "motion-data")], check=True, capture_output=True, text=True
        )
        folder = out.stdout.strip().splitlines()[-1]
    root = Path(folder).expanduser()
    for candidate in (root, root / DATASET2, root / "dataset" / DATASET2):
        if any(candidate.glob("*.bvh")):
            return candidate
    raise SystemExit(f"no .bvh files in {root} (nor in {root / DATASET2})")


def machine() -> dict:
    return {
        "cpu": cpu_name(),
        "cores": os.cpu_count(),
        "ram_gib": memory_gib(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "package": (
            f"expressive-mocap {em.__version__} ({commit(REPO)}), Rust "
            f"threads: {getattr(em.backend._core, 'num_threads', '?')}"
        ),
    }


def package_fingerprint() -> str:
    """A hash of the installed package's files (Python and the built extension): compared at the
    start and end of a run, since the package may be rebuilt while a long run is going."""
    import hashlib

    digest = hashlib.sha256()
    for path in sorted(Path(em.__file__).parent.rglob("*")):
        if path.suffix in (".py", ".so", ".pyd"):
            digest.update(path.name.encode() + path.read_bytes())
    return digest.hexdigest()[:12]


# ----------------------------------------------------------------------------- our measurements


def read_bytes(paths):
    """The floor: only get every file's bytes into memory (after the page cache is warm)."""
    return sum(len(Path(p).read_bytes()) for p in progress(paths, "bytes"))


def read_rust_many(paths):
    with em.use_backend("rust"):
        return em.read_bvh_many(progress(paths, "rust read_bvh_many"))


def read_rust_loop(paths):
    with em.use_backend("rust"):
        return [em.read_bvh(p) for p in progress(paths, "rust read_bvh loop")]


def read_numpy(paths):
    with em.use_backend("numpy"):
        return em.read_bvh_many(progress(paths, "numpy-twin read"))


def fk_all(motions, backend: str):
    """World rotations and positions of every clip through the public ``Motion.fk``."""
    with em.use_backend(backend):
        return [m.fk() for m in progress(motions, f"{backend} fk")]


HAS_FK_MANY = hasattr(em, "forward_kinematics_many")


def fk_many(motions, backend: str):
    """``em.forward_kinematics_many``: one call for all clips, parallel across clips in Rust
    (most clips are below the per-clip kernel's parallel threshold of 16,384 joint-frames)."""
    with em.use_backend(backend):
        return em.forward_kinematics_many(motions)


def reader_breakdown(paths) -> tuple[list, str]:
    """Where ``read_bvh_many`` spends its time: the reader's helpers and kernels that exist in
    this version are wrapped with timers for one call (a call made inside a timed call, in the
    same thread, is shown as "of which"). Steps in different threads may overlap."""
    import threading

    from expressive_mocap.bvh import reader as B

    core = em.backend._core
    spots = [
        (B, "_load", "read the files (Python)"),
        (B, "parse_header", "header: hierarchy, Frames, Frame Time (Python)"),
        (B, "_decode", "kernel call with its arguments (`_decode`, in the decoder thread)"),
        (B, "_collect", "wait for a batch's kernels, then build Motions (`_collect`, main thread)"),
        (core, "read_motion_blocks", "MOTION numbers + decode: `read_motion_blocks` (Rust, parallel across files)"),
        (em.Motion, "__init__", "`Motion.__init__` checks"),
    ]
    spent: dict[tuple, float] = {}
    local = threading.local()
    captured: dict = {}

    def wrap(fn, label):
        def timed_fn(*a, **kw):
            captured.setdefault(label, a)
            stack = local.__dict__.setdefault("stack", [])
            key = (label, stack[-1] if stack else None)
            stack.append(label)
            t0 = clock()
            try:
                return fn(*a, **kw)
            finally:
                spent[key] = spent.get(key, 0.0) + clock() - t0
                stack.pop()

        return timed_fn

    saved = [(owner, name, getattr(owner, name)) for owner, name, _ in spots if hasattr(owner, name)]
    labels = {name: label for _, name, label in spots}
    try:
        for owner, name, fn in saved:
            setattr(owner, name, wrap(fn, labels[name]))
        total, _ = timed(read_rust_many, paths, collect=True)
    finally:
        for owner, name, fn in saved:
            setattr(owner, name, fn)

    def children(parent, depth):
        out = []
        for (label, p), seconds in sorted(spent.items(), key=lambda kv: -kv[1]):
            if p == parent:
                out.append(("  " * depth + ("of which " if depth else "") + label, seconds))
                out += children(label, depth + 1)
        return out

    rows = [("whole `read_bvh_many` call (with the timers)", total)] + children(None, 0)
    top = sum(v for (label, parent), v in spent.items() if parent is None)
    if top <= total:
        rows.append(("other Python glue in `read_bvh_many` (the rest)", total - top))
    else:
        rows.append(
            (
                "(the steps above overlap: threads run concurrently; "
                f"their sum exceeds the call by {top - total:.3f} s)",
                top - total,
            )
        )
    # Split the fused Rust call: the number parsing alone, on exactly the inputs it was given.
    fused_label = labels["read_motion_blocks"]
    if fused_label in captured:
        try:
            blocks = [tuple(b[:4]) for b in captured[fused_label][0]]  # the first batch's blocks
            from concurrent.futures import ThreadPoolExecutor

            with em.use_backend("rust"):
                fused, _ = timed(core.read_motion_blocks, captured[fused_label][0], collect=True)
                # One block a call; the kernel releases the GIL, so the threads run in parallel.
                with ThreadPoolExecutor(core.num_threads) as pool:
                    parse_only, _ = timed(
                        lambda: list(pool.map(lambda b: core.parse_motion_block(*b), blocks)), collect=True
                    )
            size = sum(len(b[0]) - b[1] for b in blocks)
            rows.append(
                (
                    f"split of the Rust call on its first batch ({len(blocks)} "
                    f"files, {size / MB:.0f} MB, called again alone):",
                    fused,
                )
            )
            rows.append(("  parsing the numbers only (the parse kernel on the same blocks, same threads)", parse_only))
            rows.append(("  the rest: Euler->quaternion, translations, output arrays", fused - parse_only))
        except (TypeError, ValueError, IndexError) as error:
            log(f"could not split read_motion_blocks: {error}")
    # A cProfile of the whole call, to name the Python functions behind those times.
    profile = cProfile.Profile()
    gc.collect()
    with em.use_backend("rust"):
        profile.runcall(em.read_bvh_many, paths)
    text = io.StringIO()
    pstats.Stats(profile, stream=text).sort_stats("tottime").print_stats(12)
    return rows, text.getvalue()


# ----------------------------------------------------------------------------- peers


def peer_read(name: str, path: str):
    """Load one file with a peer, through the reader its users would call."""
    if name == "pymotion":
        from pymotion.io.bvh import BVH

        loaded = BVH()
        loaded.load(path)
        return loaded
    if name == "bvhio":
        import bvhio

        return bvhio.readAsHierarchy(path)
    if name == "pybvh":
        import pybvh

        # world_up given: the file is Y-up, so pybvh need not infer it (its faster path).
        return pybvh.read_bvh_file(path, world_up="+y")
    raise ValueError(name)


def peer_positions(name: str, loaded, names) -> np.ndarray:
    """World positions [F, J, 3] of the joints ``names`` from a peer's loaded object."""
    if name == "pymotion":
        from pymotion.ops.skeleton_np import fk

        rots, pos, parents, _offsets, *_ = loaded.get_data()
        # Per-frame local positions, not offsets: every Bandai joint has position channels.
        positions, _ = fk(rots, pos[:, 0], pos, parents)
        return positions
    if name == "bvhio":
        by_name = {joint.Name: joint for joint, _, _ in loaded.layout()}
        joints = [by_name[n] for n in names]
        frames = len(joints[0].Keyframes)
        out = np.empty((frames, len(joints), 3))
        for f in range(frames):
            loaded.loadPose(f)
            for j, joint in enumerate(joints):
                out[f, j] = tuple(joint.PositionWorld)
        return out
    if name == "pybvh":
        keep = [i for i, node in enumerate(loaded.nodes) if not node.is_end_site()]
        return loaded.node_positions()[:, keep]
    raise ValueError(name)


def peer_names(path: str):
    """Joint names in file order (for bvhio's name lookup); read with ours, outside the timing."""
    return em.read_bvh(path).skeleton.names


def rotation_only(motion: em.Motion) -> em.Motion:
    """The same motion on a skeleton whose non-root joints have only rotation channels
    (pybvh rejects position channels on non-root joints). Those joints then sit at their
    header offsets: the converted clips are a different motion, used for speed only."""
    sk = motion.skeleton
    channels = tuple(
        cs if j == 0 else tuple(c for c in cs if c.endswith("rotation")) for j, cs in enumerate(sk.channels)
    )
    skeleton = em.Skeleton(sk.names, sk.parents, sk.offsets, channels, sk.end_sites)
    return em.Motion(skeleton, motion.rotations, motion.translations, motion.frame_time)


def convert_for_pybvh(paths, folder: Path) -> list:
    """Write every clip once, with our writer, as a rotation-only file (6 decimals, like the originals)."""
    out = []
    with em.use_backend("rust"):
        for p in progress(paths, "convert for pybvh"):
            target = folder / Path(p).name
            em.write_bvh(rotation_only(em.read_bvh(p)), target, decimals=6)
            out.append(str(target))
    return out


# ----------------------------------------------------------------------------- child processes


def child_main(kind: str, paths_file: str) -> None:
    """One end-to-end run (read every clip, then FK of every clip) in a fresh process, so its
    RSS high-water mark belongs to that run alone. Prints one JSON line."""
    paths = json.loads(Path(paths_file).read_text())
    names = peer_names(paths[0]) if kind == "bvhio" else None
    if kind in PEERS:
        import_peer = {"pymotion": "pymotion.io.bvh", "bvhio": "bvhio", "pybvh": "pybvh"}[kind]
        __import__(import_peer)
    warnings.simplefilter("ignore")
    baseline = peak_rss()
    gc.collect()
    result: dict = {"kind": kind}
    if kind in ("rust", "numpy", "rust-read"):
        backend = "numpy" if kind == "numpy" else "rust"
        r0, t0 = resource.getrusage(resource.RUSAGE_SELF), clock()
        with em.use_backend(backend):
            motions = em.read_bvh_many(progress(paths, f"{kind}: read"))
        r1, t1 = resource.getrusage(resource.RUSAGE_SELF), clock()
        # CPU and page faults of a first read in a fresh process: all its memory is new.
        result.update(
            read_user_s=r1.ru_utime - r0.ru_utime,
            read_sys_s=r1.ru_stime - r0.ru_stime,
            read_minflt=r1.ru_minflt - r0.ru_minflt,
        )
        fk = [] if kind == "rust-read" else fk_many(motions, backend) if HAS_FK_MANY else fk_all(motions, backend)
        t2 = clock()
        result.update(read_s=t1 - t0, fk_s=t2 - t1, kept="motions and FK outputs" if fk else "motions")
        result["joint_frames"] = sum(m.n_frames * m.skeleton.n_joints for m in motions)
    else:
        # Peers: per clip read then FK; only the positions are kept (a smaller footprint than
        # ours keeps, and it spares bvhio's millions of glm objects from Python's GC).
        read_s = fk_s = 0.0
        kept = []
        for p in progress(paths, f"{kind}"):
            t0 = clock()
            loaded = peer_read(kind, p)
            t1 = clock()
            kept.append(peer_positions(kind, loaded, names))
            t2 = clock()
            read_s += t1 - t0
            fk_s += t2 - t1
            del loaded
        result.update(
            read_s=read_s, fk_s=fk_s, kept="positions only", joint_frames=sum(k.shape[0] * k.shape[1] for k in kept)
        )
    result["total_s"] = result["read_s"] + result["fk_s"]
    result["peak_rss"] = peak_rss()
    result["baseline_rss"] = baseline
    print(json.dumps(result), flush=True)


def run_child(kind: str, paths_file: str) -> dict | None:
    """A child's JSON result, or None if it failed (its traceback is on stderr): one broken
    stage should not lose the rest of a run of several minutes."""
    out = subprocess.run(
        [sys.executable, str(Path(__file__).resolve()), "--child", kind, "--paths-file", paths_file],
        stdout=subprocess.PIPE,
        text=True,
    )
    if out.returncode != 0:
        log(f"child {kind} failed with exit code {out.returncode}")
        return None
    return json.loads(out.stdout.strip().splitlines()[-1])


# ----------------------------------------------------------------------------- measurements


def same_motions(motions, reference, what: str, exact: bool = False) -> None:
    """``motions`` hold the clips of ``reference`` (Rust ``read_bvh_many``): the same count, joints
    and frames, rotations and translations equal (``exact``) or within the tolerances."""
    check_equal(len(motions), len(reference), f"{what}: clips read")
    rot_tol, pos_tol = (0.0, 0.0) if exact else (ROTATION_TOL, POSITION_TOL)
    for k, (m, ref) in enumerate(zip(motions, reference)):
        check_close(m.rotations, ref.rotations, f"{what}: rotations of clip {k}", atol=rot_tol)
        check_close(m.translations, ref.translations, f"{what}: translations of clip {k}", atol=pos_tol)


def same_fk(outputs, reference, what: str) -> None:
    """FK ``outputs`` (world rotations, positions per clip) within the tolerances of ``reference``."""
    check_equal(len(outputs), len(reference), f"{what}: clips")
    for k, ((rot, pos), (ref_rot, ref_pos)) in enumerate(zip(outputs, reference)):
        check_close(rot, ref_rot, f"{what}: world rotations of clip {k}", atol=ROTATION_TOL)
        check_close(pos, ref_pos, f"{what}: world positions of clip {k}", atol=POSITION_TOL)


def measure_read_and_fk(paths, rounds: int) -> tuple[dict, list]:
    """Rounds of read and FK, the implementations' order rotated each round (drift hits all). In
    the first round every output is checked against Rust's (``read_bvh_many``, ``m.fk()``)."""
    times: dict[str, list] = {
        k: []
        for k in (
            "floor",
            "rust_many",
            "rust_loop",
            "numpy_read",
            "rust_fk",
            "numpy_fk",
            "rust_fk_many",
            "numpy_fk_many",
        )
    }
    motions = None
    for r in range(rounds):
        # Round 0 starts with the floor, then rust_many: the reference of the checks.
        for step in rotated(["floor", "rust_many", "rust_loop", "numpy_read"], r):
            if step == "floor":
                times["floor"].append(timed(read_bytes, paths, collect=True)[0])
                continue
            fn = {"rust_many": read_rust_many, "rust_loop": read_rust_loop, "numpy_read": read_numpy}[step]
            motions_step = None
            seconds, motions_step = timed(fn, paths, collect=True)
            times[step].append(seconds)
            if step == "rust_many":
                motions = motions_step
                check_equal(len(motions), len(paths), "clips read by read_bvh_many")
            elif r == 0:
                same_motions(motions_step, motions, step, exact=step == "rust_loop")
            del motions_step
        # FK on the motions just read by read_bvh_many; outputs dropped right away (round 0: after the checks).
        fk_order = ["rust_fk", "numpy_fk"] + (["rust_fk_many", "numpy_fk_many"] if HAS_FK_MANY else [])
        reference = None
        for step in rotated(fk_order, r):
            fn = fk_many if step.endswith("_many") else fk_all
            seconds, out = timed(fn, motions, step.split("_")[0], collect=True)
            times[step].append(seconds)
            if r == 0 and step == "rust_fk":
                reference = out
            elif r == 0:
                same_fk(out, reference, step)
            del out
        del reference
        log(f"round {r + 1}/{rounds}: " + ", ".join(f"{k} {v[-1]:.3f}s" for k, v in times.items() if v))
    return times, motions


def spot_check(paths, converted, peers) -> list:
    """Max |world position - ours| (file units, cm) on a few clips, for every implementation."""
    picks = sorted({0, len(paths) // 2, len(paths) - 1})
    rows = []
    with em.use_backend("rust"):
        ours = {i: em.read_bvh(paths[i]) for i in picks}
        ours_pos = {i: ours[i].positions() for i in picks}
    rows.append(
        (
            "SciPy reference (Rotation.from_euler, composed per joint)",
            max(np.abs(scipy_positions(paths[i]) - ours_pos[i]).max() for i in picks),
        )
    )
    with em.use_backend("numpy"):
        rows.append(
            ("NumPy twin backend", max(np.abs(em.read_bvh(paths[i]).positions() - ours_pos[i]).max() for i in picks))
        )
    for name in peers:
        errors = []
        for i in picks:
            path = converted[i] if name == "pybvh" else paths[i]
            reference = em.read_bvh(path).positions() if name == "pybvh" else ours_pos[i]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                got = peer_positions(name, peer_read(name, path), ours[i].skeleton.names)
            errors.append(np.abs(got - reference).max())
        label = PEER_LABEL[name] + (
            " (on the rotation-only converted clips, vs ours on them)" if name == "pybvh" else ""
        )
        rows.append((label, max(errors)))
    for label, error in rows[:2]:  # ours against the independent reference and the twin; peers are only shown
        check(error <= POSITION_TOL, f"spot check: {label} is {error:.2g} cm from ours (more than {POSITION_TOL:g})")
    return [
        (label, err, f"{len(picks)} clips: " + ", ".join(Path(paths[i]).stem.replace("dataset-2_", "") for i in picks))
        for label, err in rows
    ]


def scipy_positions(path: str) -> np.ndarray:
    """Independent reference: the MOTION numbers by np.loadtxt, rotations by SciPy per joint in the
    written (intrinsic) order, position channels replacing the offset components they name."""
    from scipy.spatial.transform import Rotation

    skeleton = em.read_bvh(path).skeleton  # hierarchy only
    text = Path(path).read_bytes()
    start = text.index(b"\n", text.lower().index(b"frame time")) + 1
    values = np.loadtxt(io.BytesIO(text[start:]), ndmin=2)
    frames, col = len(values), 0
    world_rot, world_pos = [], []
    for j, channels in enumerate(skeleton.channels):
        local = np.tile(skeleton.offsets[j], (frames, 1))
        order, angles = "", []
        for c in channels:
            if c.endswith("position"):
                local[:, "XYZ".index(c[0])] = values[:, col]
            else:
                order += c[0]
                angles.append(values[:, col])
            col += 1
        rot = Rotation.from_euler(order, np.stack(angles, 1), degrees=True) if order else Rotation.identity(frames)
        p = skeleton.parents[j]
        if p < 0:
            world_rot.append(rot)
            world_pos.append(local)
        else:
            world_rot.append(world_rot[p] * rot)
            world_pos.append(world_pos[p] + world_rot[p].apply(local))
    return np.stack(world_pos, 1)


def measure_end_to_end(paths_file: str, conv_file: str | None, peers) -> dict:
    """Each run in a child process; ours runs right before and after every other
    implementation, so each ratio uses the neighbouring runs of ours."""
    runs: dict[str, list] = {}
    failed: list[str] = []

    def run(kind: str, file: str, key: str | None = None):
        key = key or kind
        log(f"end-to-end: {key} ...")
        result = run_child(kind, file)
        if result is None:
            failed.append(key)
            return None
        runs.setdefault(key, []).append(result)
        log(
            f"end-to-end: {key} read {result['read_s']:.2f}s + fk "
            f"{result['fk_s']:.2f}s, peak RSS {result['peak_rss'] / MB:.0f} MB"
        )
        return result

    def ratio(other, *ours):
        ours = [o["total_s"] for o in ours if o]
        return other["total_s"] / statistics.mean(ours) if other and ours else None

    def ours(file: str, key: str = "rust"):
        # Ours is cheap: 3 runs a slot, the median one counts, so one disturbed run does not.
        results = [r for r in (run("rust", file, key) for _ in range(3)) if r]
        return sorted(results, key=lambda r: r["total_s"])[len(results) // 2] if results else None

    ratios = {}
    run("rust-read", paths_file)  # memory of reading alone
    before = ours(paths_file)
    numpy_run = run("numpy", paths_file)
    after = ours(paths_file)
    ratios["numpy"] = ratio(numpy_run, before, after)
    for name in peers:
        if name == "pybvh":
            conv_before = ours(conv_file, "rust-converted")
            peer = run("pybvh", conv_file)
            ratios[name] = ratio(peer, conv_before, ours(conv_file, "rust-converted"))
        else:
            before = after
            peer = run(name, paths_file)
            after = ours(paths_file)
            ratios[name] = ratio(peer, before, after)
    return {"runs": runs, "ratios": {k: v for k, v in ratios.items() if v is not None}, "failed": failed}


def check_end_to_end(e2e: dict, joint_frames: int) -> None:
    """Every child run of ours read and posed every joint-frame of the clips it was given (the
    converted clips keep every joint and frame)."""
    for key in ("rust-read", "rust", "numpy", "rust-converted"):
        for result in e2e["runs"].get(key, []):
            check_equal(result["joint_frames"], joint_frames, f"end-to-end run {key}: joint-frames")


# ----------------------------------------------------------------------------- report


def md_table(headers, rows) -> str:
    lines = ["| " + " | ".join(headers) + " |", "|" + "|".join("---" for _ in headers) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def command_line() -> str:
    """How this script was called, from the repository root."""
    return " ".join(["python", os.path.relpath(sys.argv[0], REPO)] + sys.argv[1:])


@dataclass
class Run:
    """What one run measured, for :func:`report`.

    ``stats``: clips, bytes, frames, joint_frames and decoded (bytes of the float64 arrays) of the
    clips; ``times``: seconds of each round per step (:func:`measure_read_and_fk`); ``breakdown``
    and ``profile_text``: :func:`reader_breakdown`; ``e2e``: :func:`measure_end_to_end` (None when
    not run); ``checks``: :func:`spot_check`; ``conv_stats``: seconds and bytes of the clips
    converted for pybvh (None without it)."""

    limit: int | None
    rounds: int
    peers: list[str]
    info: dict
    stats: dict
    times: dict[str, list[float]]
    breakdown: list
    profile_text: str
    e2e: dict | None
    checks: list
    conv_stats: dict | None
    started: datetime.datetime
    elapsed: float
    command: str = field(default_factory=command_line)

    @property
    def full(self) -> bool:
        return self.limit is None

    @property
    def t(self) -> dict[str, float]:
        """The median seconds of each step."""
        return {k: median(v) for k, v in self.times.items()}

    @property
    def runs(self) -> dict[str, list[dict]]:
        return self.e2e["runs"] if self.e2e else {}

    @property
    def ratios(self) -> dict[str, float]:
        return self.e2e["ratios"] if self.e2e else {}

    def child_median(self, key: str, field: str) -> float:
        return median(x[field] for x in self.runs.get(key, []))

    def faster(self, numpy_key: str, rust_key: str) -> str:
        return f"{ratio_median(self.times[numpy_key], self.times[rust_key]):.1f}x faster than the NumPy twin"


def report(run: Run) -> str:
    """The section of benches/RESULTS.md: the run's setting, then one part per measurement."""
    out = header(run)
    out += read_part(run)
    out += fk_part(run)
    out += end_to_end_part(run)
    out += spot_check_part(run)
    out += breakdown_part(run)
    out += targets_part(run)
    return "\n".join(out)


def header(run: Run) -> list[str]:
    info, stats = run.info, run.stats
    out = [
        f"- date: {run.started:%Y-%m-%d %H:%M} (the run took {run.elapsed / 60:.1f} min)",
        f"- machine: {info['cpu']}, {info['cores']} cores, {info['ram_gib']:.1f} "
        f"GiB RAM; Python {info['python']}, NumPy {info['numpy']}",
        f"- package: {info['package']}",
        f"- command: `{run.command}`",
        f"- data: {stats['clips']} clips, {stats['bytes'] / MB:.1f} MB, "
        f"{stats['frames']:,} frames, {stats['joint_frames'] / 1e6:.2f} M joint-frames"
        + ("" if run.full else f" (first {run.limit} clips only: targets not judged)"),
        f"- method: {run.rounds} rounds of read / FK in one process, the order rotated each round (times: medians; "
        "ratios: medians of same-round ratios); end-to-end runs each in a fresh child process, ours right before "
        "and after every other implementation; page cache warm; peers single-threaded, ours on 2 threads",
        f"- {CITATION}\n",
    ]
    if info.get("changed"):
        out.append(
            "**Warning: the package's files changed during this run "
            "(rebuilt or edited): the figures mix versions; run again.**\n"
        )
    if run.e2e and run.e2e["failed"]:
        out.append(f"**Child runs that failed (see stderr): {', '.join(run.e2e['failed'])}.**\n")
    return out


def rate_row(run: Run, label: str, seconds: float, nb: int | None = None, vs: str = "") -> list[str]:
    nb = run.stats["bytes"] if nb is None else nb
    frames = run.stats["frames"]
    return [label, f"{seconds:.3f}", f"{nb / MB / seconds:.0f}", f"{frames / seconds / 1e3:.0f} k", vs]


def read_part(run: Run) -> list[str]:
    t, runs = run.t, run.runs
    rows = [
        rate_row(run, "reading the bytes only: the floor", t["floor"]),
        rate_row(run, "**ours, Rust: `read_bvh_many`**", t["rust_many"], vs=run.faster("numpy_read", "rust_many")),
        rate_row(run, "ours, Rust: `read_bvh` per file", t["rust_loop"], vs=run.faster("numpy_read", "rust_loop")),
        rate_row(run, "ours, NumPy twin backend: `read_bvh_many`", t["numpy_read"], vs="1.0x"),
    ]
    if "rust" in runs:
        cpu = (
            f"user {run.child_median('rust', 'read_user_s'):.1f} s + sys {run.child_median('rust', 'read_sys_s'):.1f} "
            f"s CPU, {run.child_median('rust', 'read_minflt') / 1e3:.0f} k page faults"
        )
        rows.append(
            rate_row(
                run,
                f"ours, Rust: `read_bvh_many`, first call in a fresh process ({len(runs['rust'])} runs)",
                run.child_median("rust", "read_s"),
                vs=cpu,
            )
        )
    for name in run.peers:
        if name not in runs:
            continue
        r = runs[name][0]
        if name == "pybvh" and "rust-converted" in runs:
            ours = run.child_median("rust-converted", "read_s")
            rows.append(
                rate_row(
                    run,
                    f"{PEER_LABEL[name]} `read_bvh_file`, converted clips (1 run)",
                    r["read_s"],
                    nb=run.conv_stats["bytes"],
                    vs=f"{r['read_s'] / ours:.1f}x ours' time ({ours:.2f} s on the same files, fresh process)",
                )
            )
        elif "rust" in runs:
            ours = run.child_median("rust", "read_s")
            rows.append(
                rate_row(
                    run,
                    f"{PEER_LABEL[name]} load (1 run)",
                    r["read_s"],
                    vs=f"{r['read_s'] / ours:.1f}x ours' time in a fresh process",
                )
            )
    return [
        "### 1. Read: parse + Euler->quaternion, every clip into memory\n",
        md_table(["implementation", "wall s", "MB/s", "frames/s", "ratio / notes"], rows) + "\n",
    ]


def fk_part(run: Run) -> list[str]:
    t, runs, times = run.t, run.runs, run.times

    def fk_row(label, key, vs=""):
        return [label, f"{t[key]:.3f}", f"{run.stats['joint_frames'] / t[key] / 1e6:.1f} M", vs]

    rows = []
    if times["rust_fk_many"]:
        rows.append(
            fk_row(
                "**ours, Rust: `em.forward_kinematics_many(motions)`**",
                "rust_fk_many",
                run.faster("numpy_fk_many", "rust_fk_many"),
            )
        )
    rows.append(fk_row("ours, Rust: `m.fk()` per clip", "rust_fk", run.faster("numpy_fk", "rust_fk")))
    if times["numpy_fk_many"]:
        rows.append(fk_row("ours, NumPy twin: `em.forward_kinematics_many(motions)`", "numpy_fk_many", "1.0x"))
    rows.append(fk_row("ours, NumPy twin: `m.fk()` per clip", "numpy_fk", "1.0x"))
    for name in run.peers:
        key = "rust-converted" if name == "pybvh" else "rust"
        if name in runs and key in runs:
            r, ours = runs[name][0], run.child_median(key, "fk_s")
            rows.append(
                [
                    f"{PEER_LABEL[name]}{', converted clips' if name == 'pybvh' else ''} (1 run)",
                    f"{r['fk_s']:.3f}",
                    f"{r['joint_frames'] / r['fk_s'] / 1e6:.2f} M",
                    f"{r['fk_s'] / ours:.0f}x ours' time in a fresh process",
                ]
            )
    return [
        "### 2. Forward kinematics of every frame of every clip (same loaded motions)\n",
        md_table(["implementation", "wall s", "joint-frames/s", "ratio"], rows) + "\n",
    ]


END_TO_END_LABELS = {
    "rust-read": "ours, Rust, read only (keeps the motions)",
    "rust": "**ours, Rust**: `read_bvh_many` + "
    + ("`forward_kinematics_many`" if HAS_FK_MANY else "`m.fk()`")
    + " (keeps motions and FK outputs)",
    "numpy": "ours, NumPy twin (keeps motions and FK outputs)",
    "rust-converted": "ours, Rust, converted clips (keeps motions and FK outputs)",
}


def end_to_end_part(run: Run) -> list[str]:
    runs, ratios, decoded = run.runs, run.ratios, run.stats["decoded"]
    if not runs:
        return []
    base = min(x["baseline_rss"] for results in runs.values() for x in results)
    out = [
        "### 3. End to end (read + FK), each run in a fresh process; peak memory\n",
        "Decoded float64 arrays (rotations F*J*4*8 + translations F*J*3*8 bytes): "
        f"**{decoded / MB:.0f} MB**. Peak = the child's RSS high-water mark, `VmHWM` from "
        "/proc/self/status (`ru_maxrss` would report the parent's peak, which survives "
        f"exec), interpreter and imports included (about {base / MB:.0f} MB before reading).\n",
    ]
    rows = []
    for key, results in runs.items():
        label = (
            END_TO_END_LABELS.get(key)
            or f"{PEER_LABEL[key]}{', converted clips' if key == 'pybvh' else ''} (keeps positions only)"
        )
        peak = max(x["peak_rss"] for x in results)
        rows.append(
            [
                label,
                len(results),
                f"{run.child_median(key, 'total_s'):.2f}",
                f"{ratios[key]:.1f}x" if key in ratios else "",
                f"{peak / MB:.0f} MB",
                f"{peak / decoded:.2f}x",
            ]
        )
    headers = ["implementation", "runs", "read+FK s", "time / ours' (neighbouring runs)", "peak RSS", "peak / decoded"]
    out.append(md_table(headers, rows) + "\n")
    if run.conv_stats:
        out.append(
            "pybvh cannot read the Bandai files (it rejects position channels on non-root joints), so "
            "every clip was converted once, with our writer, to a rotation-only file (non-root joints "
            f"keep only their three rotation channels; 6 decimals): {run.conv_stats['bytes'] / MB:.1f} MB in "
            f"{run.conv_stats['seconds']:.1f} s. pybvh and ours were timed on those same converted files.\n"
        )
    return out


def spot_check_part(run: Run) -> list[str]:
    if not run.checks:
        return []
    rows = [[a, f"{b:.1e}", c] for a, b, c in run.checks]
    return [
        "### 4. Correctness spot check: world positions against ours (cm)\n",
        md_table(["implementation", "max abs difference", "clips"], rows) + "\n",
    ]


def breakdown_part(run: Run) -> list[str]:
    if not run.breakdown:
        return []
    whole = run.breakdown[0][1]
    rows = [
        [
            label.replace("  ", "&nbsp;&nbsp;&nbsp;"),
            f"{v:.3f}",
            "" if label.startswith(("split", "  parsing", "  the rest")) else f"{v / whole:.0%}",
        ]
        for label, v in run.breakdown
    ]
    profile = "\n".join(line.rstrip() for line in run.profile_text.strip().splitlines() if line.strip())
    return [
        "### 5. Where our reader's time goes (one `read_bvh_many` call, Rust backend, warm process)\n",
        md_table(["step", "s", "share of the call"], rows) + "\n",
        "cProfile of one more call (profiling inflates the Python parts):\n\n```\n" + profile[:4000] + "\n```\n",
    ]


def verdict(run: Run, value, goal_met: bool) -> str:
    if not run.full:
        return "n/a (partial run)"
    if value is None:
        return "not measured"
    return "**pass**" if goal_met else "**FAIL**"


def targets_part(run: Run) -> list[str]:
    t, times, runs, ratios, decoded = run.t, run.times, run.runs, run.ratios, run.stats["decoded"]
    targets = []

    def target(name, value, goal_met, shown):
        targets.append([name, shown, verdict(run, value, goal_met)])

    target(
        "read the whole archive < 1.5 s (`read_bvh_many`, warm process)",
        t["rust_many"],
        t["rust_many"] < 1.5,
        f"{t['rust_many']:.2f} s",
    )
    if "rust" in runs:
        v = run.child_median("rust", "read_s")
        target("... the same, first call in a fresh process", v, v < 1.5, f"{v:.2f} s")
    fk_key, fk_api = (
        ("rust_fk_many", "`forward_kinematics_many`") if times["rust_fk_many"] else ("rust_fk", "`m.fk()` per clip")
    )
    target(f"FK of everything < 0.2 s ({fk_api})", t[fk_key], t[fk_key] < 0.2, f"{t[fk_key]:.3f} s")
    if fk_key != "rust_fk":
        target("... the same with `m.fk()` per clip", t["rust_fk"], t["rust_fk"] < 0.2, f"{t['rust_fk']:.3f} s")
    r = ratio_median(times["numpy_read"], times["rust_many"])
    target("Rust >= 3x the NumPy twin on reading (`read_bvh_many`)", r, r >= 3, f"{r:.1f}x")
    r = ratio_median(times["numpy_" + fk_key[5:]], times[fk_key])
    target(f"Rust >= 20x the NumPy twin on FK ({fk_api})", r, r >= 20, f"{r:.1f}x")
    if fk_key != "rust_fk":
        r = ratio_median(times["numpy_fk"], times["rust_fk"])
        target("... the same with `m.fk()` per clip", r, r >= 20, f"{r:.1f}x")
    for name, goal in (("pymotion", 20), ("pybvh", 3)):
        r = ratios.get(name)
        target(
            f"end-to-end >= {goal}x faster than {PEER_LABEL[name]}",
            r,
            r is not None and r >= goal,
            f"{r:.1f}x" if r else "not run",
        )
    if "rust-read" in runs:
        peak = max(x["peak_rss"] for x in runs["rust-read"])
        target(
            "peak memory of reading <= 3x the decoded float64 arrays",
            peak,
            peak <= 3 * decoded,
            f"{peak / MB:.0f} MB = {peak / decoded:.2f}x {decoded / MB:.0f} MB",
        )
    if "rust" in runs:
        peak = max(x["peak_rss"] for x in runs["rust"])
        targets.append(
            ["(info) peak memory of read + FK, FK outputs kept too", f"{peak / MB:.0f} MB = {peak / decoded:.2f}x", ""]
        )
    return ["### Targets we set\n", md_table(["target", "measured", "result"], targets) + "\n"]


# ----------------------------------------------------------------------------- main


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--data", help="folder of dataset-2 .bvh files, or the unpack root (default: run ../shared/data/unpack)"
    )
    parser.add_argument(
        "--peers", default=",".join(PEERS), help="comma-separated peers to run: pymotion, bvhio, pybvh ('' for none)"
    )
    parser.add_argument("--limit", type=int, help="only the first N clips (a quick run; targets are not judged)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds of the read / FK measurements (default 3)")
    parser.add_argument(
        "--out",
        default=str(Path(__file__).resolve().parent / "RESULTS.md"),
        help=f"markdown file whose section {TITLE!r} this rewrites (the others are kept)",
    )
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--paths-file", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child_main(args.child, args.paths_file)

    args.peers = [p.strip() for p in args.peers.split(",") if p.strip()]
    if unknown := set(args.peers) - set(PEERS):
        parser.error(f"unknown peers {sorted(unknown)}; choose from {', '.join(PEERS)}")
    if not em.rust_available():
        raise SystemExit("the Rust extension is not built: pip install . (from the repository root)")
    started, t_start = datetime.datetime.now(), clock()
    info = machine()
    fingerprint = package_fingerprint()
    folder = find_data(args.data)
    paths = sorted(str(p) for p in folder.glob("*.bvh"))[: args.limit]
    log(f"{len(paths)} clips in {folder}")

    # Warm the page cache: every later read finds the bytes in memory.
    n_bytes = read_bytes(paths)
    work = Path(tempfile.mkdtemp(prefix="bench-archive-"))
    try:
        times, motions = measure_read_and_fk(paths, args.rounds)
        stats = {
            "clips": len(paths),
            "bytes": n_bytes,
            "frames": sum(m.n_frames for m in motions),
            "joint_frames": sum(m.n_frames * m.skeleton.n_joints for m in motions),
            "decoded": sum(m.rotations.nbytes + m.translations.nbytes for m in motions),
        }
        del motions
        log("reader breakdown ...")
        breakdown, profile_text = reader_breakdown(paths)

        converted, conv_stats, conv_file = None, None, None
        if "pybvh" in args.peers:
            seconds, converted = timed(convert_for_pybvh, paths, work)
            conv_stats = {"seconds": seconds, "bytes": read_bytes(converted)}  # also warms their cache
            conv_file = str(work / "converted.json")
            Path(conv_file).write_text(json.dumps(converted))
        paths_file = str(work / "paths.json")
        Path(paths_file).write_text(json.dumps(paths))

        log("correctness spot check ...")
        checks = spot_check(paths, converted, args.peers)
        e2e = measure_end_to_end(paths_file, conv_file, args.peers)
        check_end_to_end(e2e, stats["joint_frames"])
    finally:
        shutil.rmtree(work, ignore_errors=True)

    if package_fingerprint() != fingerprint:
        info["changed"] = True
        log("WARNING: the package's files changed during the run: the figures mix versions")
    run = Run(
        limit=args.limit,
        rounds=args.rounds,
        peers=args.peers,
        info=info,
        stats=stats,
        times=times,
        breakdown=breakdown,
        profile_text=profile_text,
        e2e=e2e,
        checks=checks,
        conv_stats=conv_stats,
        started=started,
        elapsed=clock() - t_start,
    )
    text = report(run)
    print(text)
    write_section(TITLE, text, args.out)
    log(f"wrote the section {TITLE!r} of {args.out}")


if __name__ == "__main__":
    main()
