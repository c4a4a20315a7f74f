"""Elbows and knees after every edit, measured independently of the package: each edit is
written to BVH, its hierarchy and numbers read by this script's own parser, composed with SciPy,
and each hinge's signed flexion taken in the upper segment's frame about the axis the input
itself bends it about (the mean normal of the two segments over its frames bent 25 degrees or
more): 0 straight, negative bent backwards.

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0). The walks model is the one of
experiments/exaggeration_experiment.py (walks exhausted/normal/active = levels 1/2/3, takes 1-8 as
people); every dataset-2 walk (175 clips) is exaggerated to levels 0-4 with the hinge limits and
without, modulated to 0 and 2 with the shipped body-mechanics model, mixed with a wave (its body
mechanics, the wave's expressiveness) and blended into the wave; a CMU walk (CMU Graphics Lab
Motion Capture Database, subject 131) is modulated on the canonical body and carried back.

Writes experiments/HINGES.md and experiments/figures/hinges_walks.png. Run:

    PYTHONPATH=python python experiments/hinge_limits.py [DATA_DIR] [OTHER_DIR]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import sys
import warnings
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap._utils.files import atomic_write
from expressive_mocap.body.hinges import CANONICAL_AXES, NEUTRAL_MOST
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.edits import blend, mix, modulate
from expressive_mocap.exaggeration import exaggerate, train
from expressive_mocap.skeletons.canonical import carried_for
from independent import scipy_fk

HERE = Path(__file__).resolve().parent
DEFAULT_DATA = Path.home() / ".cache/motion-data/dataset/Bandai-Namco-Research-Motiondataset-2/data"
DEFAULT_OTHER = HERE.parent.parent / "shared" / "data" / "other"
LEVELS = (0.0, 1.0, 2.0, 3.0, 4.0)
TOLERANCE = 0.5
NEUTRAL = ("walk", "walk-turn-left", "walk-turn-right", "run")
BANDAI = {
    f"{side} {hinge}": tuple(f"{part}_{side}" for part in parts)
    for hinge, parts in {"elbow": ("UpperArm", "LowerArm", "Hand"), "knee": ("UpperLeg", "LowerLeg", "Foot")}.items()
    for side in "LR"
}
CMU = {
    f"{side[0]} {hinge}": tuple(part.format(side) for part in parts)
    for hinge, parts in {"elbow": ("{}Shoulder", "{}Elbow", "{}Wrist"), "knee": ("{}Hip", "{}Knee", "{}Ankle")}.items()
    for side in ("Left", "Right")
}


# --- an independent BVH reader and SciPy forward kinematics -------------------------------------


def segments(fk, limb: tuple[str, str, str]) -> tuple[np.ndarray, np.ndarray]:
    names, rotations, positions = fk
    top, middle, end = (names.index(n) for n in limb)
    inverse = rotations[top].inv()
    return inverse.apply(positions[:, middle] - positions[:, top]), inverse.apply(
        positions[:, end] - positions[:, middle]
    )


def bend_axis(upper: np.ndarray, lower: np.ndarray) -> np.ndarray:
    normal = np.cross(upper, lower)
    cos = np.sum(upper * lower, 1) / np.linalg.norm(upper, axis=1) / np.linalg.norm(lower, axis=1)
    angle = np.degrees(np.arccos(np.clip(cos, -1, 1)))
    bent = angle >= 25 if (angle >= 25).sum() >= 3 else angle >= np.percentile(angle, 90)
    axis = (normal[bent] / np.linalg.norm(normal[bent], axis=1, keepdims=True)).mean(axis=0)
    return axis / np.linalg.norm(axis)


def flexion(upper: np.ndarray, lower: np.ndarray, axis: np.ndarray) -> np.ndarray:
    lower = lower - np.outer(lower @ axis, axis)
    return np.degrees(np.arctan2(np.cross(upper, lower) @ axis, np.sum(upper * lower, 1)))


class Measure:
    """Flexion of the hinges of edits of one input, about the input's own axes."""

    def __init__(self, original: em.Motion, limbs: dict):
        self.limbs = limbs
        fk = scipy_fk(em.bvh_bytes(original).decode())
        self.axes = {h: bend_axis(*segments(fk, limb)) for h, limb in limbs.items()}

    def __call__(self, motion: em.Motion) -> dict[str, np.ndarray]:
        fk = scipy_fk(em.bvh_bytes(motion).decode())
        return {h: flexion(*segments(fk, limb), self.axes[h]) for h, limb in self.limbs.items()}


def summary(angles: dict[str, np.ndarray]) -> tuple[float, float, float]:
    """(most degrees past straight over every hinge, largest elbow flexion, largest knee flexion)."""
    back = max(0.0, -min(float(a.min()) for a in angles.values()))
    elbow = max(float(a.max()) for h, a in angles.items() if "elbow" in h)
    knee = max(float(a.max()) for h, a in angles.items() if "knee" in h)
    return back, elbow, knee


# --- the experiment ------------------------------------------------------------------------------


def neutral_limits(data: Path) -> list[str]:
    """Each hinge's axis and most flexion over dataset-2's neutral locomotion, measured here."""
    files = [f for kind in NEUTRAL for f in sorted(data.glob(f"dataset-2_{kind}_normal_*.bvh"))]
    most = {h: -np.inf for h in BANDAI}
    axes: dict[str, list[np.ndarray]] = {h: [] for h in BANDAI}
    for f in files:
        fk = scipy_fk(f.read_text())
        for h, limb in BANDAI.items():
            up, low = segments(fk, limb)
            axes[h].append(bend_axis(up, low))
            most[h] = max(most[h], float(flexion(up, low, axes[h][-1]).max()))
    roles = {
        "L elbow": "left_forearm",
        "R elbow": "right_forearm",
        "L knee": "left_lower_leg",
        "R knee": "right_lower_leg",
    }
    rows = [
        f"Measured here over the {len(files)} dataset-2 neutral locomotion clips (`{{walk,walk-turn-left,"
        "walk-turn-right,run}_normal_*`, the shipped body-mechanics model's training data), against the "
        "constants the package ships for the canonical body (`expressive_mocap.body.hinges`):",
        "",
        "| hinge | most flexion here (deg) | shipped | mean axis here (upper joint's frame) | shipped axis |",
        "|---|---|---|---|---|",
    ]
    for h, role in roles.items():
        mean = np.mean(axes[h], axis=0)
        mean /= np.linalg.norm(mean)
        rows.append(
            f"| {h} | {most[h]:.1f} | {NEUTRAL_MOST[role]:.1f} | {np.round(mean, 3).tolist()} | "
            f"{list(CANONICAL_AXES[role])} |"
        )
    return rows


def main() -> None:
    data = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT_DATA
    other = Path(sys.argv[2]) if len(sys.argv) > 2 else DEFAULT_OTHER
    warnings.simplefilter("ignore")  # estimates outside the trained range, of the styled walks
    styles = ("exhausted", "normal", "active")
    people = [[em.read_bvh(data / f"dataset-2_walk_{s}_{p:03d}.bvh") for s in styles] for p in range(1, 9)]
    model = train(people, (1.0, 2.0, 3.0))
    limits = model.hinge_limits
    walks = sorted(data.glob("dataset-2_walk_*.bvh"))
    body_model = BodyModel.load()
    wave = em.read_bvh(data / "dataset-2_wave-right-hand_active_001.bvh")

    # results[(edit, limited)] = list of (back, elbow, knee); speeds for the exaggerations
    results: dict[tuple[str, bool], list[tuple[float, float, float]]] = {}
    speeds: dict[bool, list[float]] = {True: [], False: []}
    inputs = []
    for n, path in enumerate(walks):
        walk = em.read_bvh(path)
        measure = Measure(walk, BANDAI)
        inputs.append(summary(measure(walk)))
        for on in (False, True):
            for level in LEVELS:
                out, report = exaggerate(model, walk, level, hinges=on)
                results.setdefault((f"exaggerate to {level:g}", on), []).append(summary(measure(out)))
                speeds[on].append(report.stance_speed_output / max(report.stance_speed_input, 1e-9))
            for scale in (0.0, 2.0):
                out = modulate(walk, scale, body_model, hinges=on)
                results.setdefault((f"modulate x{scale:g}", on), []).append(summary(measure(out)))
            results.setdefault(("mix: walk's body, wave's expressiveness", on), []).append(
                summary(measure(mix(walk, wave, body_model, hinges=on)))
            )
            blended = blend(walk, wave, body_model, (60, 90), (40, 120), hinges=on)
            results.setdefault(("blend walk -> wave", on), []).append(summary(measure(blended)))
        if n % 25 == 0:
            print(f"{n + 1}/{len(walks)} walks", file=sys.stderr)

    cmu_rows = []
    cmu_path = other / "cmu_scaled_131_03.bvh"
    if cmu_path.exists():
        cmu = em.read_bvh(cmu_path)
        carried = carried_for(cmu, body_model)
        measure = Measure(cmu, CMU)
        for scale in (0.0, 2.0, 3.0):
            row = []
            for on in (False, True):
                out = carried.back(modulate(carried.body, scale, body_model, hinges=on), hinges=on)
                row.append(summary(measure(out)))
            cmu_rows.append(
                f"| modulate x{scale:g} | {row[0][0]:.1f} | {row[1][0]:.2f} | {row[0][1]:.1f} / {row[0][2]:.1f} | "
                f"{row[1][1]:.1f} / {row[1][2]:.1f} |"
            )
    write(results, speeds, inputs, limits, neutral_limits(data), cmu_rows, len(walks))
    figure(results)


def write(results, speeds, inputs, limits, neutral_rows, cmu_rows, n_walks) -> None:
    table = limits.table()
    inputs_arr = np.array(inputs)
    lines = [
        "# Hinge limits: elbows and knees after every edit",
        "",
        "Generated by `PYTHONPATH=python python experiments/hinge_limits.py` from the "
        "Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0) and, for the retargeted edit, a CMU walk "
        "(CMU Graphics Lab Motion Capture Database, subject 131). Measured independently of the package: "
        "each edit written to BVH, read by the script's own parser, composed with SciPy; each hinge's signed "
        "flexion in the upper segment's frame about the axis the input bends it about (0 straight, < 0 "
        "backwards). 'past straight' is the most any hinge of an edit bends backwards, in degrees.",
        "",
        f"The {n_walks} dataset-2 walks as they are: at most {inputs_arr[:, 0].max():.2f} deg past straight, "
        f"elbows flexed up to {inputs_arr[:, 1].max():.1f} deg, knees up to {inputs_arr[:, 2].max():.1f}.",
        "",
        "Limits the walks model learnt from its training cycles (takes 1-8 of exhausted/normal/active; from "
        "straight to the most flexion plus 10% of the range): "
        + ", ".join(f"{j} 0-{hi:.1f} deg" for j, (_, hi) in table.items())
        + ".",
        "",
        "| edit of every walk | past straight, no limits: max (edits > 0.5) | with limits: max (edits > 0.5) "
        "| largest elbow / knee flexion, no limits | with limits |",
        "|---|---|---|---|---|",
    ]
    for (edit, on), rows in results.items():
        if on:
            continue
        off_arr, on_arr = np.array(rows), np.array(results[(edit, True)])
        lines.append(
            f"| {edit} | {off_arr[:, 0].max():.1f} ({int((off_arr[:, 0] > TOLERANCE).sum())}) | "
            f"{on_arr[:, 0].max():.2f} ({int((on_arr[:, 0] > TOLERANCE).sum())}) | "
            f"{off_arr[:, 1].max():.1f} / {off_arr[:, 2].max():.1f} | "
            f"{on_arr[:, 1].max():.1f} / {on_arr[:, 2].max():.1f} |"
        )
    lines += [
        "",
        "Stance-foot speed of the exaggerations (output / input, from the reports): with no limits "
        f"{np.max(speeds[False]):.3f} at most, with limits {np.max(speeds[True]):.3f} at most (the knees are "
        "limited before the feet are locked).",
        "",
        "![past straight per edit, no limits and with limits](figures/hinges_walks.png)",
        "",
        "## The canonical body's limits",
        "",
        *neutral_rows,
    ]
    if cmu_rows:
        lines += [
            "",
            "## A retargeted edit",
            "",
            "The CMU walk modulated on the canonical body with the shipped model and carried back onto its own "
            "skeleton; measured on the CMU skeleton about the axes its own capture bends each hinge about. "
            "'No limits' is the edit carried back without them (on the body and on the user's skeleton).",
            "",
            "| edit | past straight, no limits | with limits | elbow / knee flexion, no limits | with limits |",
            "|---|---|---|---|---|",
            *cmu_rows,
        ]
    atomic_write(HERE / "HINGES.md", ("\n".join(lines) + "\n").encode())
    print("\n".join(lines))


def figure(results) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    edits = [e for e, on in results if not on]
    fig, ax = plt.subplots(figsize=(9, 4))
    for k, edit in enumerate(edits):
        for on, colour, dx in ((False, "tab:red", -0.15), (True, "tab:blue", 0.15)):
            values = np.array(results[(edit, on)])[:, 0]
            jitter = np.random.default_rng(k).uniform(-0.08, 0.08, len(values))
            ax.scatter(k + dx + jitter, values, s=6, color=colour, alpha=0.5, label=None)
    ax.scatter([], [], color="tab:red", label="no limits")
    ax.scatter([], [], color="tab:blue", label="with hinge limits")
    ax.set_xticks(range(len(edits)))
    ax.set_xticklabels([e.replace(": walk's body, wave's expressiveness", " walk+wave") for e in edits], rotation=30)
    ax.set_ylabel("degrees past straight (most of any hinge)")
    ax.set_title("Every dataset-2 walk edited (Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0)")
    ax.legend()
    fig.tight_layout()
    fig.savefig(HERE / "figures" / "hinges_walks.png", dpi=110)


if __name__ == "__main__":
    main()
