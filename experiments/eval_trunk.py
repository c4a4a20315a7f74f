"""Is a walk's lean in its trunk's expressive component? Spine and chest activity and the lean
that ``modulate --scale 0`` leaves, with the trunk read joint by joint (as before) and as one chain.

    python experiments/eval_trunk.py [--data DIR]

Lean: the hips-to-neck line from vertical in the plane of the facing direction (from the line
between the upper legs) and the up axis, forward positive, mean over frames, measured with this
folder's own reader and SciPy forward kinematics on the files ``modulate`` writes. Activity: the
mean over frames of Spine and Chest. The clips: dataset-2's walks (the training session),
takes 9-16 of each style, uncalibrated; dataset-1's walks to the left, right and back (another
session) in the styles that lean and the normal one, uncalibrated and calibrated on that session's
three normal sidestep walks (``calibrate``, thresholds included).

Data: Bandai-Namco-Research-Motiondataset 1 and 2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling import BodyModel, decompose
from expressive_mocap.viz.render import render_poses
from independent import read_fk
from setting import REPO, arguments, bandai_dir, described

LEANING = ("old", "tired", "sad", "not-confident")
SIDESTEPS = ("walk-left", "walk-right", "walk-back")


def lean(path: Path) -> float:
    """Mean trunk lean of a BVH file, degrees (see the module's docstring)."""
    fk = read_fk(path)
    p = fk.positions
    at = {n: k for k, n in enumerate(fk.names)}
    trunk = p[:, at["Neck"]] - p[:, at["Hips"]]
    side = p[:, at["UpperLeg_L"]] - p[:, at["UpperLeg_R"]]
    side[:, 1] = 0.0
    forward = np.cross(side, [0.0, 1.0, 0.0])
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    return float(np.degrees(np.arctan2(np.sum(trunk * forward, axis=1), trunk[:, 1])).mean())


def measure(path: Path, models: dict[str, BodyModel], work: Path) -> dict[str, float]:
    """The clip's lean, and per model its trunk activity and the lean at modulation 0."""
    motion = em.read_bvh(path)
    row = {"lean": lean(path)}
    for name, model in models.items():
        parts = decompose(motion, model)
        row[f"{name} activity"] = float(parts.activity[:, [2, 3]].mean())
        out = work / f"{name}.bvh"
        em.write_bvh(parts.recompose(0.0), out)
        row[f"{name} lean 0"] = lean(out)
    return row


def table(title: str, rows: dict[str, list[dict[str, float]]]) -> list[str]:
    lines = [
        f"### {title}",
        "",
        "| clips | lean | spine+chest activity: joints / chain | lean at --scale 0: joints / chain |",
        "|---|---|---|---|",
    ]
    for label, found in rows.items():
        m = {k: np.mean([r[k] for r in found]) for k in found[0]}
        lines.append(
            f"| {label} | {m['lean']:.1f} | {m['joints activity']:.3f} / {m['chain activity']:.3f} "
            f"| {m['joints lean 0']:.1f} / {m['chain lean 0']:.1f} |"
        )
    return lines + [""]


def main() -> None:
    args = arguments(__doc__)
    two, one = bandai_dir(args.data, 2), bandai_dir(args.data, 1)
    shipped = BodyModel.load()
    neutral = [em.read_bvh(one / f"dataset-1_{m}_normal_001.bvh") for m in SIDESTEPS]
    calibrated = shipped.calibrated(neutral)
    sessions = {
        "uncalibrated": {"joints": replace(shipped, trunk=None), "chain": shipped},
        "calibrated": {"joints": replace(calibrated, trunk=None), "chain": calibrated},
    }
    lines = [
        "# The trunk's lean in the expressive component",
        "",
        described(__doc__),
        "",
        f"Chain thresholds: the shipped model's {shipped.trunk.scale:.3f} (the lean it leaves on its held-out "
        f"neutral clips at the 95th percentile reads as 10 degrees); calibrated on dataset-1's sidesteps "
        f"{calibrated.trunk.scale:.3f}.",
        "",
        "`python experiments/eval_trunk.py`. Data: Bandai-Namco-Research-Motiondataset 1 and 2 (CC BY-NC 4.0).",
        "",
    ]
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        styles = ("normal", "elderly", "exhausted", "active", "youthful", "feminine", "masculine")
        rows = {
            f"dataset-2 walk {s}, takes 9-16": [
                measure(two / f"dataset-2_walk_{s}_{k:03d}.bvh", sessions["uncalibrated"], work) for k in range(9, 17)
            ]
            for s in styles
        }
        lines += table("Dataset-2 (the training session), uncalibrated", rows)
        for session, models in sessions.items():
            rows = {
                f"{move} {style}": [measure(one / f"dataset-1_{move}_{style}_001.bvh", models, work)]
                for move in SIDESTEPS
                for style in ("normal", *LEANING)
            }
            lines += table(f"Dataset-1 (another session), {session}", rows)
            print(f"{session} done", flush=True)
    figure = REPO / "experiments" / "figures" / "trunk_lean.png"
    walk = em.read_bvh(one / "dataset-1_walk-left_not-confident_001.bvh")
    render_poses(
        [walk, decompose(walk, calibrated).recompose(0.0)],
        figure,
        ["not-confident walk (dataset-1)", "modulate --scale 0, calibrated"],
        view="side",
    )
    lines += [
        "Seen from the side: a leaning walk of dataset-1 and its body mechanics (the model calibrated as above):",
        "",
        "![a not-confident walk and its body mechanics, side view](figures/trunk_lean.png)",
        "",
    ]
    (REPO / "experiments" / "TRUNK.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
