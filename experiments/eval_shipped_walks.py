"""What the shipped exaggeration models do to held-out takes, as a viewer would measure it.

    python experiments/eval_shipped_walks.py [--data DIR]

For every shipped model, dataset-2's held-out takes of its action (take 9 on of its axis' three
styles: never trained on) are measured with this folder's own reader and SciPy forward
kinematics: a locomotion model's with the gait measures of experiments/exaggeration_sessions.py,
an arm action's with gesture measures (the highest hand above the head's mean height, both
hands' paths about their shoulders, the elbows' mean flexion, the trunk's mean lean, and the
gesture's duration: the frames a hand is at least 30 % of its farthest from where it rests at
the clip's ends). Each held-out take of the middle style is exaggerated to 3 and diminished to 1
by the model (`exaggerate --action A --axis X`, default settings; posture measures without
retiming, `--no-timing`; speed, cadence and duration, which move with the timing only, with it);
per measure, how far its mean moves from the middle style's towards the heaviest (to 3) or the
lightest (to 1) style's (1: all the way; the bar a shipped model is held to: at least 0.5).
Also: stance feet (the edit's mean stance-foot speed over the input's, through the input's
contacts; bar 1.2x) and hinges (the largest knee or elbow angle past straight, degrees: 0 when
none bends backwards).

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

import expressive_mocap as em
from exaggeration_sessions import MEASURES, gait, world_positions
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.exaggeration import exaggerate
from expressive_mocap.exaggeration.edit import stance_foot_speed
from expressive_mocap.exaggeration.zoo import LOCOMOTION, PEOPLE, ShippedModel, shipped_models
from expressive_mocap.viz.render import render_poses
from hinge_limits import BANDAI, Measure, summary
from setting import REPO, arguments, bandai_dir, described

GESTURE_MEASURES = (
    ("highest hand above the head (cm)", "the higher hand's highest point over the head's mean height"),
    ("hands' path (cm)", "both hands' paths about their shoulders"),
    ("elbow flexion (deg)", "mean over frames and both arms"),
    ("trunk lean (deg)", "hips-to-neck line from vertical, forward positive, mean"),
    ("duration (s)", "frames a hand is at least 30 % of its farthest from rest"),
)
TIMED = ("speed", "cadence", "duration")  # measures that move with the timing only


def gesture(motion: em.Motion) -> np.ndarray:
    """The measures of :data:`GESTURE_MEASURES`."""
    p = world_positions(motion)
    at = {name: p[:, motion.skeleton.index(name)] for name in motion.skeleton.names}
    highest = max(at["Hand_L"][:, 1].max(), at["Hand_R"][:, 1].max()) - at["Head"][:, 1].mean()
    about = [at[f"Hand_{s}"] - at[f"UpperArm_{s}"] for s in "LR"]
    path = sum(np.linalg.norm(np.diff(a, axis=0), axis=1).sum() for a in about)
    elbows = []
    for s in "LR":
        upper, lower = at[f"LowerArm_{s}"] - at[f"UpperArm_{s}"], at[f"Hand_{s}"] - at[f"LowerArm_{s}"]
        cos = np.sum(upper * lower, 1) / (np.linalg.norm(upper, axis=1) * np.linalg.norm(lower, axis=1))
        elbows.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    forward = sum(at[f"Toes_{s}"] - at[f"Foot_{s}"] for s in "LR")
    forward[:, 1] = 0
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    trunk = at["Neck"] - at["Hips"]
    lean = np.degrees(np.arctan2(np.sum(trunk * forward, 1), trunk[:, 1]))
    moving = np.zeros(len(p), bool)
    for a in about:
        away = np.linalg.norm(a - np.concatenate([a[:3], a[-3:]]).mean(0), axis=1)
        moving |= away >= 0.3 * away.max()
    frames = np.flatnonzero(moving)
    duration = (frames[-1] - frames[0]) * motion.frame_time if len(frames) else 0.0
    return np.array([highest, path, np.mean(elbows), lean.mean(), duration])


def section(dataset: Path, shipped: ShippedModel) -> list[str]:
    """One shipped model's table."""
    low, middle, high = shipped.styles
    takes = {s: sorted(dataset.glob(f"dataset-2_{shipped.action}_{s}_*.bvh"))[len(PEOPLE) :] for s in shipped.styles}
    walking = shipped.action in LOCOMOTION
    measure: Callable[[em.Motion], np.ndarray] = gait if walking else gesture
    names = [name for name, _ in (MEASURES if walking else GESTURE_MEASURES)]
    measured = {s: np.array([measure(em.read_bvh(p)) for p in paths]).mean(0) for s, paths in takes.items()}
    model = shipped.load()
    edited: dict[float, list[np.ndarray]] = {3.0: [], 1.0: []}
    timed: dict[float, list[np.ndarray]] = {3.0: [], 1.0: []}
    feet, hinges = [], []
    for path in takes[middle]:
        take = em.read_bvh(path)
        contacts = foot_contacts(take)
        hinge = Measure(take, BANDAI)  # flexion about the input's own axes: negative past straight
        for to in edited:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                out, _ = exaggerate(model, take, to, timing=False)
                timed[to].append(measure(exaggerate(model, take, to)[0]))
            edited[to].append(measure(out))
            if walking:
                feet.append(stance_foot_speed(out, contacts) / stance_foot_speed(take, contacts))
            hinges.append(summary(hinge(out))[0])
    lines = [
        f"## {shipped.name}: {len(takes[middle])} {middle} takes edited; held-out {low} / {high} takes: "
        f"{len(takes[low])} / {len(takes[high])}",
        "",
        f"| measure | {low} | {middle} | {high} | {middle} to 1 | {middle} to 3 | share of the way to 1 | to 3 |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for k, name in enumerate(names):
        source = timed if name.startswith(TIMED) else edited
        to1, to3 = (np.mean([g[k] for g in source[to]]) for to in (1.0, 3.0))
        centre = measured[middle][k]
        shares = [
            (to - centre) / (far - centre) if abs(far - centre) > 1e-9 else float("nan")
            for to, far in ((to1, measured[low][k]), (to3, measured[high][k]))
        ]
        values = (measured[low][k], centre, measured[high][k], to1, to3)
        lines.append(
            f"| {name} | " + " | ".join(f"{v:.1f}" for v in values) + f" | {shares[0]:.2f} | {shares[1]:.2f} |"
        )
    if feet:
        lines.append(
            f"\n- stance feet, edit over input: mean {np.mean(feet):.2f}x, largest {np.max(feet):.2f}x (bar 1.2x)"
        )
    lines += [f"- knees and elbows past straight: largest {np.max(hinges):.1f} degrees", ""]
    return lines


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    lines = [
        "# The shipped exaggeration models on held-out takes",
        "",
        described(__doc__),
        "",
        "`python experiments/eval_shipped_walks.py`. Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0).",
        "",
    ]
    for shipped in shipped_models():
        lines += section(dataset, shipped)
        print(shipped.name, flush=True)
    walks = [m for m in shipped_models() if m.action == "walk"]
    if walks:
        path = sorted(dataset.glob("dataset-2_walk_normal_*.bvh"))[len(PEOPLE)]
        walk = em.read_bvh(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            edits = [exaggerate(walks[0].load(), walk, to)[0] for to in (1.0, 3.0)]
        render_poses(
            [edits[0], walk, edits[1]],
            REPO / "experiments" / "figures" / "shipped_walk.png",
            ["to 1 (diminished)", f"{path.stem} (held out)", "to 3 (exaggerated)"],
            poses=6,
        )
        lines += ["![a held-out normal walk diminished to 1 and exaggerated to 3](figures/shipped_walk.png)", ""]
    (REPO / "experiments" / "SHIPPED_WALKS.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
