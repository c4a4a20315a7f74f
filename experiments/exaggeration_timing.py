"""Timing as part of intensity, measured on real walks with independent code.

Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0): the walks model of
experiments/exaggeration_experiment.py (takes 1-8 of `exhausted` < `normal` < `active` as people,
intensities 1 < 2 < 3). Every held-out `normal` walk (takes 9-24, in no person) is exaggerated
to `active` (k = 3, its current intensity estimated) with and without timing, written to BVH and
read back here with a separate reader (NumPy text parsing, SciPy Euler rotations, own forward
kinematics; nothing of the package's measures it). Each clip's speed (the hips' horizontal travel
between its first and last footstrike over the time between them), cadence (footstrikes of both
feet per second) and stance-foot speed (the ankles' mean horizontal speed while below a
contact height) are compared with the real `active` takes 9-32 (held out too).

Writes experiments/EXAGGERATION_TIMING.md and experiments/figures/exaggeration_timing.png. Run:

    PYTHONPATH=python python experiments/exaggeration_timing.py [DATA_DIR]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap._utils.files import atomic_write
from expressive_mocap.exaggeration import exaggerate, train
from independent import read_fk

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = Path.home() / ".cache/motion-data/dataset/Bandai-Namco-Research-Motiondataset-2/data"
STYLES = ("exhausted", "normal", "active")
LEVELS = (1.0, 2.0, 3.0)
PEOPLE = range(1, 9)
HELD_OUT_NORMAL = range(9, 25)
HELD_OUT_ACTIVE = range(9, 33)
TARGET = 3.0
CONTACT = 0.1  # an ankle touches the floor below this share of its height range above its lowest


# ------------------------------------------------------------------ an independent reader and FK


@dataclass
class Clip:
    names: list[str]
    positions: np.ndarray  # [F, J, 3] world, file units
    frame_time: float


def read_clip(path: Path) -> Clip:
    """Joint names and world positions of a BVH file (the experiments' own reader and SciPy FK)."""
    fk = read_fk(path)
    return Clip(fk.names, fk.positions, fk.frame_time)


@dataclass
class Gait:
    speed: float  # file units / s
    cadence: float  # steps / s
    stance_speed: float  # file units / s


def gait(clip: Clip) -> Gait:
    """Speed, cadence and stance-foot speed from world positions alone."""
    p, dt = clip.positions, clip.frame_time
    hips = p[:, clip.names.index("Hips")]
    strikes, stance = [], []
    for side in "LR":
        ankle = p[:, clip.names.index(f"Foot_{side}")]
        low, high = np.percentile(ankle[:, 1], [2, 98])
        down = ankle[:, 1] < low + CONTACT * (high - low)
        edges = np.diff(np.r_[0, down.astype(np.int8), 0])
        starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        strikes += [int(a) for a, b in zip(starts, ends) if b - a >= 3 and a > 0]
        v = np.linalg.norm(np.diff(ankle[:, [0, 2]], axis=0), axis=1) / dt
        stance.append(v[down[1:] & down[:-1]])
    strikes.sort()
    span = (strikes[-1] - strikes[0]) * dt
    travel = np.linalg.norm(hips[strikes[-1], [0, 2]] - hips[strikes[0], [0, 2]])
    return Gait(travel / span, (len(strikes) - 1) / span, float(np.concatenate(stance).mean()))


def measured(motion: em.Motion) -> Gait:
    """The gait of a package motion, measured after writing it out and reading it back here."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "edit.bvh"
        em.write_bvh(motion, path)
        return gait(read_clip(path))


# ------------------------------------------------------------------ the experiment


def main() -> None:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_DATA
    name = lambda style, take: data / f"dataset-2_walk_{style}_{take:03d}.bvh"  # noqa: E731
    people = [[em.read_bvh(name(s, p)) for s in STYLES] for p in PEOPLE]
    model = train(people, LEVELS)
    active = [gait(read_clip(name("active", t))) for t in HELD_OUT_ACTIVE]
    goal = Gait(*(float(np.mean([getattr(g, f) for g in active])) for f in ("speed", "cadence", "stance_speed")))
    trained = [gait(read_clip(name("active", t))) for t in PEOPLE]
    seen = Gait(*(float(np.mean([getattr(g, f) for g in trained])) for f in ("speed", "cadence", "stance_speed")))
    rows, share, share_seen = [], {True: [], False: []}, []
    points = []
    for take in HELD_OUT_NORMAL:
        walk = em.read_bvh(name("normal", take))
        before = gait(read_clip(name("normal", take)))
        after = {}
        for timing in (True, False):
            out, report = exaggerate(model, walk, TARGET, timing=timing)
            after[timing] = measured(out)
            share[timing].append(
                [
                    (after[timing].speed - before.speed) / (goal.speed - before.speed),
                    (after[timing].cadence - before.cadence) / (goal.cadence - before.cadence),
                ]
            )
        share_seen.append(
            [
                (after[True].speed - before.speed) / (seen.speed - before.speed),
                (after[True].cadence - before.cadence) / (seen.cadence - before.cadence),
            ]
        )
        points.append((before, after[True], after[False]))
        rows.append(
            f"| {take:03d} | {report.k0:.2f} | {before.speed:.1f} / {before.cadence:.2f} | "
            f"{after[True].speed:.1f} / {after[True].cadence:.2f} | {after[False].speed:.1f} / "
            f"{after[False].cadence:.2f} | {share[True][-1][0]:.2f} / {share[True][-1][1]:.2f} | "
            f"{before.stance_speed:.1f} | {after[True].stance_speed:.1f} | {after[False].stance_speed:.1f} |"
        )
    on, off, on_seen = np.array(share[True]), np.array(share[False]), np.array(share_seen)
    stance_ratio = np.array([a.stance_speed / b.stance_speed for b, a, _ in points])
    figure = HERE / "figures" / "exaggeration_timing.png"
    plot(points, active, trained, figure)
    p_dur, p_travel = model.timing_predictability  # type: ignore[misc]
    report = [
        "# Timing as part of intensity: dataset-2 walks",
        "",
        "Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0). Model: walks `exhausted` < `normal` < "
        f"`active` as 1 < 2 < 3, takes {PEOPLE.start}-{PEOPLE.stop - 1} as people (as in EXAGGERATION.md). "
        f"Held out: `normal` takes {HELD_OUT_NORMAL.start}-{HELD_OUT_NORMAL.stop - 1}, each exaggerated to k = "
        f"{TARGET:g} (current intensity estimated), and `active` takes {HELD_OUT_ACTIVE.start}-"
        f"{HELD_OUT_ACTIVE.stop - 1}, the real higher intensity.",
        "Every figure is measured by this script's own BVH reader and forward kinematics (SciPy rotations) on the "
        "files the package writes: speed = the hips' horizontal travel between the first and last footstrike over "
        "the time between them (cm/s); cadence = footstrikes of both feet per second; stance-foot speed = the "
        f"ankles' mean horizontal speed while below {CONTACT:.0%} of their height range (cm/s).",
        "Produced by `PYTHONPATH=python python experiments/exaggeration_timing.py`.",
        "",
        "The model's timing at each trained level (the people's means, followed level to level): cycle "
        f"duration {' / '.join(f'{np.exp(v):.3f}' for v in model.timing_mappings[0])} s, travel per cycle "  # type: ignore[index]
        f"{' / '.join(f'{np.exp(v):.3f}' for v in model.timing_mappings[1])} actor heights; their mean "  # type: ignore[index]
        f"|correlation| with the intensity over every training cycle {p_dur:.2f} / {p_travel:.2f} (applied at >= 0.5).",
        "",
        f"Real `active` takes {HELD_OUT_ACTIVE.start}-{HELD_OUT_ACTIVE.stop - 1}: speed {goal.speed:.1f} cm/s, cadence "
        f"{goal.cadence:.2f} steps/s (means); the training people's own `active` takes {PEOPLE.start}-"
        f"{PEOPLE.stop - 1}: {seen.speed:.1f} cm/s, {seen.cadence:.2f} steps/s (the actor's active cadence rises "
        f"take after take, from {min(g.cadence for g in trained):.2f} to {max(g.cadence for g in active):.2f}, "
        "while the normal takes stay within 1.77-1.88).",
        "",
        "| take | k0 | in: speed / cadence | k = 3, timing | k = 3, no timing | share of the way, timing "
        "(speed / cadence) | stance speed in | timing | no timing |",
        "|---|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "| measure | with timing | without |",
        "|---|---|---|",
        f"| share of the way to the active mean, speed (mean, lowest) | {on[:, 0].mean():.2f} ({on[:, 0].min():.2f}) "
        f"| {off[:, 0].mean():.2f} ({off[:, 0].min():.2f}) |",
        f"| share of the way, cadence (mean, lowest) | {on[:, 1].mean():.2f} ({on[:, 1].min():.2f}) | "
        f"{off[:, 1].mean():.2f} ({off[:, 1].min():.2f}) |",
        f"| walks at least halfway in both | {int(np.all(on >= 0.5, axis=1).sum())} of {len(on)} | "
        f"{int(np.all(off >= 0.5, axis=1).sum())} of {len(off)} |",
        f"| share of the way to the training people's active mean, speed / cadence (mean) | "
        f"{on_seen[:, 0].mean():.2f} / {on_seen[:, 1].mean():.2f} | |",
        f"| stance-foot speed, out / in (mean, largest) | {stance_ratio.mean():.2f} ({stance_ratio.max():.2f}) | |",
        "",
        "Target: speed and cadence at least halfway (share >= 0.5) to the real active takes' means.",
        "",
        f"![speed and cadence](figures/{figure.name})",
        "",
    ]
    atomic_write(HERE / "EXAGGERATION_TIMING.md", "\n".join(report).encode())
    print("\n".join(report))


def plot(points, active, trained, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    ax.scatter([g.cadence for g in active], [g.speed for g in active], c="tab:red", s=18, label="active, held out")
    ax.scatter([g.cadence for g in trained], [g.speed for g in trained], facecolors="none", edgecolors="tab:red", s=22,
               label="real active (training takes)")  # fmt: skip
    ax.scatter([b.cadence for b, _, _ in points], [b.speed for b, _, _ in points], c="tab:blue", s=18,
               label="held-out normal (input)")  # fmt: skip
    ax.scatter([a.cadence for _, _, a in points], [a.speed for _, _, a in points], c="0.6", marker="x", s=22,
               label="k = 3, no timing")  # fmt: skip
    ax.scatter([a.cadence for _, a, _ in points], [a.speed for _, a, _ in points], c="k", marker="^", s=22,
               label="k = 3, timing")  # fmt: skip
    for b, a, _ in points:
        ax.annotate("", (a.cadence, a.speed), (b.cadence, b.speed), arrowprops={"arrowstyle": "->", "color": "0.7"})
    ax.set_xlabel("cadence (steps/s)")
    ax.set_ylabel("speed (cm/s)")
    ax.set_title("Bandai dataset-2 walks exaggerated to active (CC BY-NC 4.0)", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
