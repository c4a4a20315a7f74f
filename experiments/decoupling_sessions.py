"""Expressive hand motion across capture sessions and onto the idle arm:
python experiments/decoupling_sessions.py [--data DIR] [--out NAME.md] [--held-out]

"Hand motion" of a clip = mean over frames of the world distance between a joint's position at
modulation 0 (body mechanics only) and 1 (the original), positions from an independent SciPy
forward kinematics (not the package's). Two measures:

- another session (dataset-1), the model calibrated on that session's neutral locomotion
  `walk-left/right/back`, `run`, `dash` (normal style): what its neutral forward walks keep as
  expressive, against the gesturing hand of its one-hand gestures (`bye` and `guide`: right hand;
  `respond`: left hand, chosen by how far each hand moves in the original clips). The forward
  walks `dataset-1_walk_normal_*` are the held-out check, measured only with --held-out (kept
  out of every choice); the development figure is a leave-one-out over the calibration clips
  (calibrate on four, measure the fifth);
- the model's own session (dataset-2): one-hand gesture clips (`wave-left/right-hand`,
  `raise-up-left/right-hand`, every style), 30% of them by clip (seed 0, the split the package
  uses): how far the other (idle) hand moves.

and, on dataset-1's one-hand gestures (`bye`, `byebye`, `guide`, `respond`: checks, never tuned
on), the idle hand's motion about its shoulder in world axes (the hand that moves less about its
shoulder in the original), uncalibrated and calibrated.

Each is measured twice: before (every joint filtered on its own) and as the package does now (the
upper arms and forearms filtered in world axes: expressive_mocap.decoupling.arms). Calibration
sets each joint's activity threshold above the session's neutral residue.

Data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022;
Kobayashi et al., arXiv:2306.08861), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap.decoupling.algebra import decompose
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.training import split_by_group
from expressive_mocap.rotations import quat
from expressive_mocap.viz.render import render

HERE = Path(__file__).resolve().parent
JOINTS = [
    "Spine",
    "Chest",
    "Neck",
    "Head",
    "Shoulder_L",
    "UpperArm_L",
    "LowerArm_L",
    "Hand_L",
    "Shoulder_R",
    "UpperArm_R",
    "LowerArm_R",
    "Hand_R",
]
CALIBRATION = ("walk-left", "walk-right", "walk-back", "run", "dash")  # dataset-1, normal style
ONE_HAND_1 = {"bye": "R", "guide": "R", "respond": "L"}  # dataset-1 content -> gesturing hand
ONE_HAND_2 = {
    "wave-left-hand": "L",
    "wave-right-hand": "R",
    "raise-up-left-hand": "L",
    "raise-up-right-hand": "R",
}


def scipy_fk(motion: em.Motion) -> np.ndarray:
    """World positions ``[F, J, 3]`` from local rotations and translations, composed with SciPy."""
    frames, joints = motion.rotations.shape[:2]
    world: list[Rotation] = []
    positions = np.zeros((frames, joints, 3))
    for j, parent in enumerate(motion.skeleton.parents):
        local = Rotation.from_quat(motion.rotations[:, j])
        if parent < 0:
            world.append(local)
            positions[:, j] = motion.translations[:, j]
        else:
            world.append(world[parent] * local)
            positions[:, j] = positions[:, parent] + world[parent].apply(motion.translations[:, j])
    return positions


def expressive_motion(motion: em.Motion, model) -> np.ndarray:
    """Per frame and joint ``[F, J]``: the distance between modulation 0 and 1 (file units)."""
    parts = decompose(motion, model)
    gap = scipy_fk(parts.recompose(0.0)) - scipy_fk(parts.recompose(1.0))
    return np.linalg.norm(gap, axis=-1)


def frame_mean(motions, model) -> np.ndarray:
    """Per joint ``[J]``: :func:`expressive_motion` averaged over all frames of ``motions``."""
    return np.concatenate([expressive_motion(m, model) for m in motions]).mean(axis=0)


def gesture_split(data2: Path) -> tuple[list[Path], list[Path]]:
    """Dataset-2's one-hand gesture clips, 70/30 by clip (seed 0): ``(training, held out)``."""
    paths = [p for content in ONE_HAND_2 for p in sorted(data2.glob(f"dataset-2_{content}_*.bvh"))]
    train, test = split_by_group(np.arange(len(paths)), 0.3, 0)
    return [paths[k] for k in train], [paths[k] for k in test]


def table(rows: dict[str, np.ndarray], names: tuple[str, ...]) -> str:
    shown = [names.index(n) for n in JOINTS]
    lines = [
        "| clips | " + " | ".join(n.replace("_", " ") for n in JOINTS) + " |",
        "|" + "---|" * (len(JOINTS) + 1),
    ]
    for label, values in rows.items():
        lines.append(f"| {label} | " + " | ".join(f"{values[j]:.1f}" for j in shown) + " |")
    return "\n".join(lines)


def session_one(data1: Path, model: BodyModel, calibrate, held_out: bool) -> tuple[list[str], dict]:
    """Dataset-1 rows and summary for ``model`` calibrated by ``calibrate(model, clips)``."""
    names = model.joint_names
    hand = {"L": names.index("Hand_L"), "R": names.index("Hand_R")}
    other = {"L": "R", "R": "L"}
    neutral = em.read_bvh_many([data1 / f"dataset-1_{c}_normal_001.bvh" for c in CALIBRATION])
    calibrated = calibrate(model, neutral)
    rows: dict[str, np.ndarray] = {}
    gesturing, idle = [], []  # per frame
    for content, side in ONE_HAND_1.items():
        paths = sorted(data1.glob(f"dataset-1_{content}_*.bvh"))
        values = np.concatenate([expressive_motion(m, calibrated) for m in em.read_bvh_many(paths)])
        rows[f"{content}, {len(paths)} clips (gesturing hand {side})"] = values.mean(axis=0)
        gesturing.append(values[:, hand[side]])
        idle.append(values[:, hand[other[side]]])
    gesture = float(np.concatenate(gesturing).mean())
    # Development figure: each calibration clip left out, the model calibrated on the others.
    loo = np.concatenate(
        [expressive_motion(m, calibrate(model, [n for n in neutral if n is not m])) for m in neutral]
    ).mean(axis=0)
    rows[f"{'/'.join(CALIBRATION)}, each left out of calibration"] = loo
    summary = {"gesture": gesture, "idle": float(np.concatenate(idle).mean()), "loo": loo[[hand["L"], hand["R"]]]}
    if held_out:
        walks = sorted(data1.glob("dataset-1_walk_normal_*.bvh"))
        held = frame_mean(em.read_bvh_many(walks), calibrated)
        rows[f"forward walks `walk_normal_*`, {len(walks)} clips (held out)"] = held
        summary["held_out"] = held[[hand["L"], hand["R"]]]
    lines = [table(rows, names), ""]
    lines.append(
        f"- gesturing hand of the one-hand gestures: **{gesture:.1f} cm** (the other hand: {summary['idle']:.1f} cm)"
    )
    for key, what in (("loo", "calibration clips, each left out in turn"), ("held_out", "forward walks, held out")):
        if key in summary:
            left, right = summary[key]
            lines.append(
                f"- neutral {what}: hands L {left:.1f} / R {right:.1f} cm, the larger "
                f"**{max(left, right) / gesture:.3f}x** the gesturing hand"
            )
    return lines + [""], summary


ARM = ["Shoulder", "UpperArm", "LowerArm", "Hand"]
IDLE_1 = ("bye", "byebye", "guide", "respond")  # dataset-1's one-hand gestures (checks)


def session_one_idle(data1: Path, model: BodyModel) -> tuple[list[str], dict]:
    """Dataset-1's one-hand gestures, per style: the idle hand's motion about its shoulder (the
    hand that moves less so in the original) in the original and in the body mechanics, with the
    model uncalibrated and calibrated on the session's neutral locomotion."""
    names = model.joint_names
    calibrated = model.calibrated(em.read_bvh_many([data1 / f"dataset-1_{c}_normal_001.bvh" for c in CALIBRATION]))
    per_style: dict[str, list] = {}
    paths = [p for c in IDLE_1 for p in sorted(data1.glob(f"dataset-1_{c}_*.bvh"))]
    for path, motion in zip(paths, em.read_bvh_many(paths)):
        whole = scipy_fk(motion)
        own, side = min((about_shoulder(whole, names, s), s) for s in "LR")
        bodies = [scipy_fk(decompose(motion, m).recompose(0.0)) for m in (model, calibrated)]
        per_style.setdefault(path.stem.split("_")[2], []).append(
            (own, *(about_shoulder(b, names, side) for b in bodies))
        )
    lines = [
        "| style | clips | actor's idle hand (cm) | body mechanics, uncalibrated | within + 0.5 cm "
        "| calibrated | within + 0.5 cm |",
        "|---|---|---|---|---|---|---|",
    ]
    every = []
    for style, rows in sorted(per_style.items()):
        a = np.array(rows)
        every.append(a)
        lines.append(
            f"| {style} | {len(a)} | {a[:, 0].mean():.2f} | {a[:, 1].mean():.2f} "
            f"| {(a[:, 1] <= a[:, 0] + 0.5).sum()} | {a[:, 2].mean():.2f} | {(a[:, 2] <= a[:, 0] + 0.5).sum()} |"
        )
    a = np.concatenate(every)
    within = [float(np.mean(a[:, k] <= a[:, 0] + 0.5)) for k in (1, 2)]
    worse = [sum(float(np.mean(b[:, k] > b[:, 0] + 0.5)) > 0.5 for b in every) for k in (1, 2)]
    lines += [
        "",
        f"- idle hand within the actor's own + 0.5 cm: **{100 * within[0]:.0f} %** of {len(a)} clips uncalibrated, "
        f"**{100 * within[1]:.0f} %** calibrated; styles where it moves more than the actor's in most clips: "
        f"{worse[0]} uncalibrated, {worse[1]} calibrated (of {len(every)})",
        "",
    ]
    return lines, {"within": within, "worse_styles": worse}


def variation(rotations: np.ndarray) -> float:
    """Mean angle (degrees) of ``rotations [F, 4]`` from their mean rotation."""
    mean = quat.mean_rotation(rotations)
    return float(np.degrees(quat.angle(quat.mul(rotations, quat.conjugate(mean)[None]))).mean())


def about_shoulder(positions: np.ndarray, names: tuple[str, ...], side: str) -> float:
    """Mean distance (file units) of the hand from its mean place relative to its shoulder: how
    much the arm itself moves, whatever the body does."""
    hand = positions[:, names.index(f"Hand_{side}")] - positions[:, names.index(f"Shoulder_{side}")]
    return float(np.linalg.norm(hand - hand.mean(axis=0), axis=-1).mean())


def session_two(data2: Path, model: BodyModel) -> tuple[list[str], dict]:
    """Dataset-2 rows (per style, the arms as gesturing and idle) and summary for ``model``."""
    names = model.joint_names
    other = {"L": "R", "R": "L"}
    rows: dict[str, list] = {}
    # per style, per clip: idle hand (cm), idle upper arm held and varying (degrees), its variation
    # in the original and the prediction (degrees), the idle hand's motion around its mean (cm),
    # and its motion about its shoulder in the original and in the body mechanics (cm)
    idle: dict[str, list] = {}
    _, paths = gesture_split(data2)
    for path, motion in zip(paths, em.read_bvh_many(paths)):
        content, style = path.stem.split("_")[1:3]
        side = ONE_HAND_2[content]
        parts = decompose(motion, model)
        body, whole = scipy_fk(parts.recompose(0.0)), scipy_fk(parts.recompose(1.0))
        gap = body - whole
        values = np.linalg.norm(gap, axis=-1)
        columns = JOINTS[:4] + [f"{j}_{side}" for j in ARM] + [f"{j}_{other[side]}" for j in ARM]
        rows.setdefault(style, []).append(values[:, [names.index(c) for c in columns]])
        upper_arm = names.index(f"UpperArm_{other[side]}")
        idle_hand = gap[:, names.index(f"Hand_{other[side]}")]
        arm = quat.log(parts.expressive[:, upper_arm])
        held = arm.mean(axis=0)
        idle.setdefault(style, []).append(
            (
                values[:, names.index(f"Hand_{other[side]}")].mean(),
                np.degrees(np.linalg.norm(held)),
                np.degrees(np.linalg.norm(arm - held, axis=-1).mean()),
                variation(motion.rotations[:, upper_arm]),
                variation(model.predict(motion)[:, upper_arm]),
                np.linalg.norm(idle_hand - idle_hand.mean(axis=0), axis=-1).mean(),
                about_shoulder(whole, names, other[side]),
                about_shoulder(body, names, other[side]),
            )
        )
    header = JOINTS[:4] + [f"gesturing {j}" for j in ARM] + [f"idle {j}" for j in ARM]
    lines = ["| style (clips) | " + " | ".join(header) + " |", "|" + "---|" * (len(header) + 1)]
    for style, v in sorted(rows.items()):
        mean = np.concatenate(v).mean(axis=0)
        lines.append(f"| {style} ({len(v)}) | " + " | ".join(f"{x:.1f}" for x in mean) + " |")
    lines += [
        "",
        "| style | clips | idle hand, mean over clips (cm) | largest (cm) | clips at 3 cm or more "
        "| idle upper arm's expressive rotation: held | varying "
        "| idle upper arm's variation: original | predicted (degrees) "
        "| idle hand's motion around its mean (cm) | clips at 3 cm or more |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    per_style = {style: np.array(v) for style, v in sorted(idle.items())}
    for style, a in per_style.items():
        lines.append(
            f"| {style} | {len(a)} | {a[:, 0].mean():.2f} | {a[:, 0].max():.1f} | {(a[:, 0] >= 3).sum()} "
            f"| {a[:, 1].mean():.0f} | {a[:, 2].mean():.0f} | {a[:, 3].mean():.1f} | {a[:, 4].mean():.1f} "
            f"| {a[:, 5].mean():.2f} | {(a[:, 5] >= 3).sum()} |"
        )
    lines += [
        "",
        "The idle hand's own motion about its shoulder (around its mean over the clip), in the original and in "
        "the body mechanics the network predicts:",
        "",
        "| style | original (cm) | body mechanics (cm) | clips at 3 cm or more: original | body mechanics "
        "| body mechanics within the original's + 0.5 cm | largest body mechanics (cm) |",
        "|---|---|---|---|---|---|---|",
    ]
    for style, a in per_style.items():
        within = int((a[:, 7] <= a[:, 6] + 0.5).sum())
        lines.append(
            f"| {style} | {a[:, 6].mean():.2f} | {a[:, 7].mean():.2f} "
            f"| {(a[:, 6] >= 3).sum()} | {(a[:, 7] >= 3).sum()} | {within} of {len(a)} | {a[:, 7].max():.2f} |"
        )
    own = np.concatenate([a[:, 6] for a in per_style.values()])
    predicted = np.concatenate([a[:, 7] for a in per_style.values()])
    within = float(np.mean(predicted <= own + 0.5))
    lines += [
        "",
        f"- the body-mechanics idle hand moves about its shoulder no more than the actor's own + 0.5 cm in "
        f"**{100 * within:.0f} %** of the {len(own)} clips (target 95 %); in normal-style gestures at most "
        f"{per_style['normal'][:, 7].max():.2f} cm (target 1.5)"
        if "normal" in per_style
        else "",
    ]
    every = np.concatenate([a[:, 0] for a in per_style.values()])
    moving = np.concatenate([a[:, 5] for a in per_style.values()])
    summary = {
        "clips": len(every),
        "mean": float(every.mean()),
        "over_3cm": int((every >= 3).sum()),
        # per style: idle hand (cm), clips at 3 cm or more, its motion about the shoulder (cm):
        # original, body mechanics
        "styles": {
            style: (a[:, 0].mean(), int((a[:, 0] >= 3).sum()), a[:, 6].mean(), a[:, 7].mean())
            for style, a in per_style.items()
        },
    }
    lines += [
        "",
        f"- idle hand over all {len(every)} clips: mean {every.mean():.2f} cm, "
        f"**{summary['over_3cm']} clips at 3 cm or more**; its motion around its own mean (the held "
        f"posture left out): {moving.mean():.2f} cm, {(moving >= 3).sum()} clips at 3 cm or more",
        "",
    ]
    return lines, summary


IDLE_FIGURE = ("wave-right-hand_masculine_001", "wave-left-hand_active_006")  # largest idle hands of two styles


def idle_figure(data2: Path, models: dict[str, BodyModel]) -> str:
    """Two one-hand gestures whose idle hand moves most, each with its body mechanics by each model."""
    motions, titles = [], []
    for stem in IDLE_FIGURE:
        motion = em.read_bvh(data2 / f"dataset-2_{stem}.bvh")
        motions.append(motion)
        titles.append(stem.replace("_", " "))
        for label, model in models.items():
            motions.append(decompose(motion, model).recompose(0.0))
            titles.append(f"body mechanics, {label}")
    path = HERE / "figures" / "idle_arm_styles.png"
    render(motions, path, titles, view="front", poses=4)
    return f"![idle arms: {', '.join(IDLE_FIGURE)}, original and body mechanics](figures/{path.name})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", help="folder holding Bandai-Namco-Research-Motiondataset-{1,2}")
    parser.add_argument("--out", help="markdown file written into experiments/ (default: print only)")
    parser.add_argument("--held-out", action="store_true", help="also measure dataset-1's forward walks")
    args = parser.parse_args()
    started = time.time()
    root = Path(args.data) if args.data else Path.home() / ".cache" / "motion-data" / "dataset"
    data1 = root / "Bandai-Namco-Research-Motiondataset-1" / "data"
    data2 = root / "Bandai-Namco-Research-Motiondataset-2" / "data"
    shipped = BodyModel.load()
    variants = {
        "before: every joint filtered on its own": replace(shipped, arms=None),
        "now: the upper arms and forearms filtered in world axes": shipped,
    }
    one, idle_one, two = [], [], []
    for label, model in variants.items():
        lines, _ = session_one(data1, model, lambda m, clips: m.calibrated(clips), args.held_out)
        one += [f"### {label}", "", *lines]
        lines, _ = session_one_idle(data1, model)
        idle_one += [f"### {label}", "", *lines]
        lines, _ = session_two(data2, model)
        two += [f"### {label}", "", *lines]
    command = f"python experiments/decoupling_sessions.py{' --held-out' if args.held_out else ''}"
    report = [
        "# Expressive hand motion across sessions and onto the idle arm",
        "",
        f"- date: {time.strftime('%Y-%m-%d %H:%M')}; the shipped model; command: `{command}`",
        "- data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022; "
        "Kobayashi et al., arXiv:2306.08861), CC BY-NC 4.0.",
        "- per joint: mean over all frames of its world displacement between modulation 0 (body mechanics "
        "only) and 1 (the original), in cm (positions from SciPy forward kinematics).",
        "",
        "## Dataset-1 (another session), calibrated on its "
        + ", ".join(f"`{c}`" for c in CALIBRATION)
        + " (normal style)",
        "",
        *one,
        "## Dataset-1's one-hand gestures (checks): the idle hand about its shoulder, per style",
        "",
        *idle_one,
        "## Dataset-2 (the model's session, uncalibrated): one-hand gestures of the test split, per style",
        "",
        *two,
        "Where the idle hand moves, it is partly the style's own posture, held through the clip (masculine, the idle "
        "hand on the hip) and the style's own motion of that arm, and, before, partly the network's: filtered joint "
        "by joint, the idle arm kept the actor's local rotations on the trunk the network predicted, and swung with "
        "every difference between the two trunks (the hips move with each wave). Filtered in world axes, it hangs as "
        "the actor's does. The two clips whose idle hand moves most, drawn with their body mechanics before and now:",
        "",
        idle_figure(data2, {"before": variants["before: every joint filtered on its own"], "now": shipped}),
        "",
        f"(took {time.time() - started:.0f} s)",
    ]
    text = "\n".join(report) + "\n"
    if args.out:
        (HERE / args.out).write_text(text)
    print(text)


if __name__ == "__main__":
    main()
