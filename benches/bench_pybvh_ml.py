"""expressive-mocap preprocess against pybvh-ml's preprocess_directory, on the same files.

    python benches/bench_pybvh_ml.py [--data DIR] [--limit N] [--rounds 3] [--work DIR] [--write-results]
    python benches/bench_pybvh_ml.py --other-rig FILE.bvh [--clips 500] [--seconds 5] ...

pybvh-ml 0.6.0 (``pip install -r benches/requirements-pybvh-ml.txt``) turns a folder of BVH
files into one .npz of per-clip arrays: rotations (6D here), joint velocities, foot contacts.
``expressive-mocap preprocess --rotations 6d --keep rotations,velocities,contacts`` writes the
same kinds. The bench detects which of those options this checkout has and, without them, times
the closest run it offers (quaternion rotations, positions, contacts), saying so.

pybvh (under pybvh-ml) cannot read the Bandai-Namco files: they have position channels on every
joint. And on the Bandai skeleton its foot contacts refuse the rest pose: the root, joint_Root,
lies on the floor under the hips with the bones along X, so the feet are "above the hips". So
every clip is written once, with our writer, as the same motion on a skeleton pybvh-ml takes:
joint_Root folded into Hips (the new root, 6 channels), the other joints rotation-only, and
the first clip's first frame as the rest pose of all (offsets and local rotations re-expressed
so every joint's world position is unchanged, to rounding; one skeleton for all, as in the
originals). Both programs are timed on those files.

``--other-rig FILE.bvh`` measures an archive of another skeleton instead: a file pybvh reads as it
is (a CMU clip: 31 joints, 120 fps, position channels on the root only) cut into ``--clips``
overlapping windows of ``--seconds`` each, evenly spread over it, written once with our writer;
its own section of the results.

Each run is a fresh child process (imports included in its wall time; the call itself is also
timed inside the child), pybvh-ml and ours alternated round after round; medians. Both packages
are byte-compiled first, as pip leaves an installed wheel: pybvh-ml's modules were, at its
install, while an editable checkout of ours under PYTHONDONTWRITEBYTECODE (set here) compiled all
its modules from source at every start, 60 ms of each process. Checked before the figures are
written (benches/harness.py; a failed check raises): pybvh's world positions of a converted clip
within 1e-3 cm of ours on the original (the conversion writes 6 decimals), and both datasets
holding every clip and the same frames.
Data: Bandai-Namco-Research-Motiondataset, dataset-2 (Bandai Namco Research Inc., 2022), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from harness import Stopwatch, byte_compile, check, check_equal, commit, cpu_name, memory_gib, rotated

DATA = Path.home() / ".cache" / "motion-data" / "dataset" / "Bandai-Namco-Research-Motiondataset-2" / "data"
RESULTS = Path(__file__).parent / "RESULTS.md"
SECTION = "Preprocessing against pybvh-ml: `benches/bench_pybvh_ml.py`"
SECTION_OTHER = "Preprocessing against pybvh-ml, another rig: `benches/bench_pybvh_ml.py --other-rig`"
ROTATION_CHANNELS = ("Zrotation", "Xrotation", "Yrotation")
ROOT_CHANNELS = ("Xposition", "Yposition", "Zposition", *ROTATION_CHANNELS)
SANITY_CM = 1e-3  # pybvh on a converted clip against ours on the original: 2e-06 cm recorded


# ----------------------------------------------------------------------------- the converted files


def rest_of(reference: em.Motion) -> list[Rotation]:
    """Every joint's world rotation in the first frame of ``reference``: the rest pose of all the
    converted files (one pose for all, so they share one skeleton, as the originals do)."""
    world_q, _ = reference.fk()
    return [Rotation.from_quat(world_q[0, j]) for j in range(reference.skeleton.n_joints)]


def for_pybvh_ml(motion: em.Motion, rest: list[Rotation]) -> em.Motion:
    """The same motion without joint_Root (Hips the root), rotation channels only below it, and
    the rest pose ``rest`` (Q_j, world rotations): the new offset of a child c of j is Q_j t_c
    (t_c: its bone, the same in every frame and clip of dataset-2), j's new world rotation
    W_j(t) Q_j^-1 (its local one W'_p(t)^-1 W'_j(t)), so every world position stays where it was."""
    sk = motion.skeleton
    assert sk.names[0] == "joint_Root" and sk.parents[1] == 0, "expects the Bandai-Namco skeleton"
    world_q, world_p = motion.fk()
    keep = list(range(1, sk.n_joints))
    new_world = [Rotation.from_quat(world_q[:, j]) * rest[j].inv() for j in range(sk.n_joints)]
    parents = [-1 if sk.parents[j] == 0 else sk.parents[j] - 1 for j in keep]
    offsets = np.zeros((len(keep), 3))
    rotations = np.empty((motion.n_frames, len(keep), 4))
    translations = np.empty((motion.n_frames, len(keep), 3))
    for new, j in enumerate(keep):
        p = sk.parents[j]
        if p == 0:  # the new root: its world pose, at its world position
            rotations[:, new] = new_world[j].as_quat()
            translations[:, new] = world_p[:, j]
        else:
            offsets[new] = rest[p].apply(motion.translations[0, j])
            rotations[:, new] = (new_world[p].inv() * new_world[j]).as_quat()
            translations[:, new] = offsets[new]
    end_sites = tuple((j - 1, tuple(rest[j].apply(np.asarray(o)))) for j, o in sk.end_sites)
    channels = tuple(ROOT_CHANNELS if parent < 0 else ROTATION_CHANNELS for parent in parents)
    skeleton = em.Skeleton(tuple(sk.names[j] for j in keep), parents, offsets, channels, end_sites)
    return em.Motion(skeleton, rotations, translations, motion.frame_time)


def convert(paths: list[Path], folder: Path) -> dict:
    """Every clip written once into ``folder`` (kept between runs of the bench)."""
    done = folder / "converted.json"
    if done.exists() and json.loads(done.read_text())["clips"] == len(paths):
        return json.loads(done.read_text())
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    with Stopwatch() as watch:
        rest = rest_of(em.read_bvh(paths[0]))
        for path in paths:
            em.write_bvh(for_pybvh_ml(em.read_bvh(path), rest), folder / path.name, decimals=6)
    record = {
        "clips": len(paths),
        "seconds": watch.seconds,
        "mb": sum(p.stat().st_size for p in folder.glob("*.bvh")) / 1e6,
    }
    done.write_text(json.dumps(record))
    return record


def cut(path: Path, clips: int, seconds: float, folder: Path) -> dict:
    """``clips`` windows of ``seconds`` of one file, evenly spread over it, written into ``folder``
    (kept between runs of the bench): an archive of that file's skeleton and frame rate."""
    done = folder / "cut.json"
    key = {"source": str(path), "clips": clips, "seconds": seconds}
    if done.exists() and {k: json.loads(done.read_text()).get(k) for k in key} == key:
        return json.loads(done.read_text())
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    motion = em.read_bvh(path)
    length = round(seconds * motion.fps)
    check(length < motion.n_frames, f"{path} has {motion.n_frames} frames, fewer than --seconds {seconds:g}")
    starts = np.linspace(0, motion.n_frames - length, clips).round().astype(int)
    with Stopwatch() as watch:
        for number, start in enumerate(starts):
            em.write_bvh(motion[start : start + length], folder / f"{path.stem}_{number:04d}.bvh", decimals=6)
    record = {**key, "seconds_taken": watch.seconds, "mb": sum(p.stat().st_size for p in folder.glob("*.bvh")) / 1e6}
    done.write_text(json.dumps(record))
    return record


def sanity(original: Path | None, converted: Path) -> dict:
    """World positions of one clip (cm): pybvh on the converted file against ours on the
    original (joint_Root dropped; when there is one) and on the converted file."""
    import pybvh

    theirs = pybvh.read_bvh_file(converted, world_up="+y").joint_positions()
    ours_converted = em.read_bvh(converted).positions()
    ours_original = ours_converted if original is None else em.read_bvh(original).positions()[:, 1:]
    return {
        "clip": converted.stem,
        "frames": len(theirs),
        "vs_original": float(np.abs(theirs - ours_original).max()),
        "vs_converted": float(np.abs(theirs - ours_converted).max()),
    }


# ----------------------------------------------------------------------------- the timed runs

CHILD = r"""
import json, sys, time
started = time.perf_counter()
kind, src, out, options = sys.argv[1], sys.argv[2], sys.argv[3], json.loads(sys.argv[4])
if kind == "pybvh-ml":
    import pybvh_ml
    imported = time.perf_counter()
    pybvh_ml.preprocess_directory(src, out, **options)
else:
    from expressive_mocap.cli import main
    import expressive_mocap.cli.data  # preprocess's code, else loaded inside main: "the call" times work only
    imported = time.perf_counter()
    assert main(["preprocess", src, "-o", out, "-q", *options]) == 0
done = time.perf_counter()
with open("/proc/self/status") as status:
    peak = next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmHWM:"))
print(json.dumps({"call": done - imported, "imports": imported - started, "peak": peak}))
"""


def our_options() -> tuple[list[str], str]:
    """The options of our run that match pybvh-ml's, or the closest this checkout has."""
    help_text = subprocess.run(
        [sys.executable, "-m", "expressive_mocap.cli", "preprocess", "--help"], capture_output=True, text=True
    ).stdout
    if "--rotations" in help_text and "velocities" in help_text:
        return ["--rotations", "6d", "--keep", "rotations,velocities,contacts"], "same kinds"
    return ["--keep", "rotations,positions,contacts"], (
        "closest available: this checkout has no --rotations/velocities, so quaternion rotations, "
        "positions (what velocities are computed from) and contacts"
    )


PYBVH_ML = {
    "representation": "6d",
    "include_velocities": True,
    "include_foot_contacts": True,
    "world_up": "+y",  # its per-file detection picks -z on some Bandai clips (arms raised at frame 0)
}


def run(kind: str, src: Path, out: Path, options) -> dict:
    if out.exists():
        shutil.rmtree(out) if out.is_dir() else out.unlink()
    with Stopwatch() as watch:
        result = subprocess.run(
            [sys.executable, "-c", CHILD, kind, str(src), str(out), json.dumps(options)],
            capture_output=True,
            text=True,
        )
    wall = watch.seconds
    if result.returncode != 0:
        raise SystemExit(f"{kind} failed:\n{result.stderr[-3000:]}")
    record = json.loads(result.stdout.strip().splitlines()[-1])
    size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file()) if out.is_dir() else out.stat().st_size
    return {**record, "wall": wall, "output": size}


def check_outputs(ours: Path, theirs: Path, same_kinds: bool) -> dict:
    """The two datasets hold the same clips and frames; with the same kinds, how far apart the
    6D rotations are (their 6D is the first two columns of the matrix, ours too if they agree)."""
    import pybvh_ml

    ds = em.load_dataset(ours)
    data = pybvh_ml.load_preprocessed(theirs)
    clips = data["clips"]
    frames = [len(c["joint_rot"]) for c in clips]
    record = {"clips": (len(ds.names), len(clips)), "frames": (int(ds.offsets[-1]), int(sum(frames)))}
    if same_kinds:
        first = clips[0]
        record["rot6d_shape"] = (list(ds.arrays["rotations"].shape[1:]), list(first["joint_rot"].shape[1:]))
    return record


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--limit", type=int, help="the first N clips only")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--work", type=Path, default=Path("/tmp/bench_pybvh_ml"))
    parser.add_argument("--other-rig", type=Path, metavar="FILE.bvh", help="an archive cut from this file instead")
    parser.add_argument("--clips", type=int, default=500, help="--other-rig: clips to cut (default 500)")
    parser.add_argument("--seconds", type=float, default=5.0, help="--other-rig: seconds a clip (default 5)")
    parser.add_argument("--write-results", action="store_true", help=f"rewrite the section {SECTION!r}")
    args = parser.parse_args()

    import pybvh
    import pybvh_ml

    if args.other_rig:
        source = args.work / f"cut_{args.other_rig.stem}"
        made = cut(args.other_rig, args.clips, args.seconds, source)
        paths = sorted(source.glob("*.bvh"))
        print(
            f"cut {len(paths)} clips ({made['mb']:.1f} MB) from {args.other_rig.name} in {made['seconds_taken']:.1f} s"
        )
        sane = sanity(None, paths[len(paths) // 2])
        data_line = (
            f"- data: {len(paths)} windows of {args.seconds:g} s, evenly spread over {args.other_rig.name} "
            f"(written once with our writer, {made['mb']:.1f} MB; not timed)"
        )
        section, mode = (
            SECTION_OTHER,
            f" --other-rig {args.other_rig.name} --clips {args.clips} --seconds {args.seconds:g}",
        )
    else:
        paths = sorted(args.data.glob("*.bvh"))[: args.limit]
        source = args.work / "converted"
        conversion = convert(paths, source)
        print(f"converted {conversion['clips']} clips ({conversion['mb']:.1f} MB) in {conversion['seconds']:.1f} s")
        middle = paths[len(paths) // 2]  # not the clip the rest pose comes from
        sane = sanity(middle, source / middle.name)
        data_line = (
            f"- data: {len(paths)} clips of dataset-2, converted once with our writer "
            f"({conversion['mb']:.1f} MB, {conversion['seconds']:.1f} s, not timed; see the script's docstring); "
            "Bandai-Namco-Research-Motiondataset (Bandai Namco Research Inc., 2022), CC BY-NC 4.0"
        )
        section, mode = SECTION, f" --limit {args.limit}" if args.limit else ""
    print(f"sanity, {sane['clip']}: pybvh vs ours {sane['vs_original']:.2g} cm (original file), "
          f"{sane['vs_converted']:.2g} cm (converted)")  # fmt: skip
    for key in ("vs_original", "vs_converted"):
        check(sane[key] <= SANITY_CM, f"sanity {key}: pybvh {sane[key]:.2g} cm from ours (over {SANITY_CM:g})")

    ours_options, ours_note = our_options()
    print(f"ours: {' '.join(ours_options)} ({ours_note})")
    compiled = byte_compile(*(Path(m.__file__).parent for m in (pybvh_ml, pybvh, em)))
    print(f"modules byte-compiled now (the rest had bytecode): {compiled}")
    times: dict[str, list[dict]] = {"pybvh-ml": [], "ours": []}
    outputs = {"pybvh-ml": args.work / "pybvh_ml.npz", "ours": args.work / "ours"}
    load = os.getloadavg()
    watch = Stopwatch()
    for round_ in range(args.rounds):
        for kind in rotated(["pybvh-ml", "ours"], round_):
            options = PYBVH_ML if kind == "pybvh-ml" else ours_options
            times[kind].append(run(kind, source, outputs[kind], options))
            print(f"round {round_ + 1}: {kind:8s} {times[kind][-1]['wall']:.2f} s")
    elapsed = watch.elapsed()
    outputs_check = check_outputs(outputs["ours"], outputs["pybvh-ml"], ours_note == "same kinds")
    check_equal(outputs_check["clips"], (len(paths), len(paths)), "clips in ours' and pybvh-ml's datasets")
    ours_frames, their_frames = outputs_check["frames"]
    check_equal(ours_frames, their_frames, "frames in ours' dataset against pybvh-ml's")
    median = {k: {f: statistics.median(r[f] for r in v) for f in v[0]} for k, v in times.items()}
    ratio_wall = median["pybvh-ml"]["wall"] / median["ours"]["wall"]
    ratio_call = median["pybvh-ml"]["call"] / median["ours"]["call"]
    print(f"pybvh-ml / ours: {ratio_wall:.1f}x (process wall), {ratio_call:.1f}x (the call alone); {outputs_check}")

    frames = outputs_check["frames"][0]
    lines = [
        f"- date: {time.strftime('%Y-%m-%d %H:%M')} (the run took {elapsed / 60:.1f} min, conversion aside)",
        f"- machine: {cpu_name()}, {os.cpu_count()} cores, {memory_gib():.1f} GiB RAM; commit {commit()}; Python "
        f"{platform.python_version()}, NumPy {np.__version__}; pybvh-ml {pybvh_ml.__version__}, pybvh "
        f"{pybvh.__version__}, expressive-mocap {em.__version__}; load average at the start "
        f"{load[0]:.1f}, {load[1]:.1f}, {load[2]:.1f}, at the end {', '.join(f'{x:.1f}' for x in os.getloadavg())}",
        f"- command: `python benches/bench_pybvh_ml.py{mode} "
        f"--rounds {args.rounds} --write-results`; each run a fresh child process, the two alternated "
        "round after round; medians",
        f"{data_line}; {frames:,} frames",
        f"- sanity: world positions of {sane['clip']} ({sane['frames']} frames), pybvh against ours: max "
        f"{max(sane['vs_original'], sane['vs_converted']):.2g} (the file's units)",
        f"- pybvh-ml: `preprocess_directory(SRC, OUT.npz, {', '.join(f'{k}={v!r}' for k, v in PYBVH_ML.items())})`",
        f"- ours: `expressive-mocap preprocess SRC -o OUT {' '.join(ours_options)} -q` ({ours_note})",
        "- bytecode: every module of both packages byte-compiled before timing, as pip leaves an installed "
        f"wheel; compiled by this run (the others already had it): {compiled}",
        "",
        "| program | runs | process wall s | (min-max) | the call s | imports s | peak RSS | output |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for kind, label in (("pybvh-ml", f"pybvh-ml {pybvh_ml.__version__}"), ("ours", "expressive-mocap")):
        m = median[kind]
        lines.append(
            f"| {label} | {len(times[kind])} | {m['wall']:.2f} | ({min(r['wall'] for r in times[kind]):.2f}-"
            f"{max(r['wall'] for r in times[kind]):.2f}) | {m['call']:.2f} | {m['imports']:.2f} | "
            f"{m['peak'] / 1e6:.0f} MB | {m['output'] / 1e6:.0f} MB |"
        )
    verdict = {r: "**pass**" if r >= 20 else "**fail**" for r in (ratio_wall, ratio_call)}
    lines += [
        "",
        f"pybvh-ml takes {ratio_wall:.1f}x ours' time per process ({verdict[ratio_wall]}) and {ratio_call:.1f}x "
        f"for the call alone ({verdict[ratio_call]}); target: ours at least 20x faster. Both datasets hold "
        f"{outputs_check['clips'][0]} clips, {frames:,} frames.",
    ]
    print("\n".join(lines))
    if args.write_results:
        sys.path.insert(0, str(Path(__file__).parent))
        from results import write_section

        write_section(section, "\n".join(lines), RESULTS)


if __name__ == "__main__":
    main()
