"""Exaggeration across capture sessions: a model trained on the Bandai-Namco dataset-2 walks
(CC BY-NC 4.0; exhausted / normal / active = 1 / 2 / 3, takes 1-8 as people) applied to clips
of dataset-1 (another session, another actor). Prints, and with ``--write FILE`` saves as
markdown:

1. the estimated current intensity of dataset-1's tired / normal / active clips, before (the
   estimate reads each DOF's mean too: ``estimate_offsets=True``) and after (the default: how each
   DOF varies around the motion's own mean pose), and with a baseline clip of the same session;
2. gait measures of its normal walks, exaggerated to 3 before and after, beside its real active
   walk: arm swing, mean elbow flexion, largest knee flexion, hips vertical range, trunk lean and
   head height, measured on world positions composed here with SciPy from the BVH numbers (not
   with the package's forward kinematics);
3. the same measures on the real walks of both sessions at each intensity.

    PYTHONPATH=python python experiments/exaggeration_sessions.py [--development] [--write experiments/SESSIONS.md]

``--development`` leaves out dataset-1's forward walks (``dataset-1_walk_{style}_001.bvh``), the
clips the method was not tuned on (walk-left, walk-right and walk-back were used).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse
import sys
import tempfile
import warnings
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap._utils.files import atomic_write
from expressive_mocap.exaggeration import ExaggerationModel, exaggerate, train
from independent import read_fk

DATA = Path.home() / ".cache/motion-data/dataset"
STYLES = ("tired", "normal", "active")
DEVELOPMENT = ("walk-left", "walk-right", "walk-back")
HELD_OUT = "walk"
MEASURES = (
    ("arm swing, hand (cm)", "hand's range along the facing direction, relative to the hips"),
    (
        "arm swing, shoulder (deg)",
        "the upper arm's range of angles (5th to 95th percentile) from hanging, forward positive, in the "
        "plane of the facing and the up axis",
    ),
    ("elbow flexion (deg)", "mean over frames"),
    ("largest knee flexion (deg)", "95th percentile over frames"),
    ("hips vertical range (cm)", "5th to 95th percentile"),
    ("trunk lean (deg)", "hips-to-neck line from vertical, forward positive"),
    ("head height (cm)", "mean"),
    ("speed (cm/s)", "the hips' mean horizontal speed"),
    ("cadence (steps/s)", "footstrikes of both feet per second (ankle within 10% of its height range)"),
)


def session_model() -> ExaggerationModel:
    folder = DATA / "Bandai-Namco-Research-Motiondataset-2/data"
    people = [
        [em.read_bvh(folder / f"dataset-2_walk_{style}_{p:03d}.bvh") for style in ("exhausted", "normal", "active")]
        for p in range(1, 9)
    ]
    return train(people, [1, 2, 3])


def clip(content: str, style: str) -> em.Motion:
    return em.read_bvh(DATA / f"Bandai-Namco-Research-Motiondataset-1/data/dataset-1_{content}_{style}_001.bvh")


# --------------------------------------------------------------------------- independent measures


def world_positions(motion: em.Motion) -> np.ndarray:
    """``[F, J, 3]``: the motion written as BVH and read back by the experiments' own reader and
    SciPy FK (:mod:`independent`)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "motion.bvh"
        em.write_bvh(motion, path)
        return read_fk(path).positions


def _angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    cos = np.sum(a * b, axis=-1) / (np.linalg.norm(a, axis=-1) * np.linalg.norm(b, axis=-1))
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def _cadence(ankles: list[np.ndarray], frame_time: float) -> float:
    """Footstrikes of both ankles ``[F, 3]`` per second between the first and the last: onsets of
    runs of at least 3 frames within 10% of the ankle's height range above its lowest."""
    strikes = []
    for ankle in ankles:
        low, high = np.percentile(ankle[:, 1], [2, 98])
        edges = np.diff(np.r_[0, (ankle[:, 1] < low + 0.1 * (high - low)).astype(np.int8), 0])
        starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        strikes += [int(a) for a, b in zip(starts, ends) if b - a >= 3 and a > 0]
    strikes.sort()
    return (len(strikes) - 1) / ((strikes[-1] - strikes[0]) * frame_time)


def gait(motion: em.Motion) -> np.ndarray:
    """The measures of :data:`MEASURES` over the frames where the hips move at more than half
    their usual (90th percentile) horizontal speed: the walk itself, not its start and stop."""
    p = world_positions(motion)
    at = {name: p[:, motion.skeleton.index(name)] for name in motion.skeleton.names}
    speed = np.linalg.norm(np.gradient(at["Hips"][:, [0, 2]], axis=0), axis=1)
    walking = speed > 0.5 * np.percentile(speed, 90)
    # Facing: the feet's heel-to-toe direction, horizontal, averaged over both feet.
    forward = sum(at[f"Toes_{s}"] - at[f"Foot_{s}"] for s in "LR")
    forward[:, 1] = 0
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    swing = np.mean(
        [np.ptp(np.percentile(np.sum((at[f"Hand_{s}"] - at["Hips"]) * forward, 1)[walking], [5, 95])) for s in "LR"]
    )
    # At the shoulder: the hand's range also shrinks when the elbows bend (a measure of its own).
    upper_arms = [at[f"LowerArm_{s}"] - at[f"UpperArm_{s}"] for s in "LR"]
    shoulder = np.mean(
        [
            np.ptp(np.percentile(np.degrees(np.arctan2(np.sum(a * forward, 1), -a[:, 1]))[walking], [5, 95]))
            for a in upper_arms
        ]
    )
    elbow = np.mean([_angle(a, at[f"Hand_{s}"] - at[f"LowerArm_{s}"]) for a, s in zip(upper_arms, "LR")], 0)
    knee = np.mean(
        [_angle(at[f"LowerLeg_{s}"] - at[f"UpperLeg_{s}"], at[f"Foot_{s}"] - at[f"LowerLeg_{s}"]) for s in "LR"], 0
    )
    hips = np.ptp(np.percentile(at["Hips"][walking, 1], [5, 95]))
    trunk = at["Neck"] - at["Hips"]
    lean = np.degrees(np.arctan2(np.sum(trunk * forward, 1), trunk[:, 1]))
    return np.array(
        [
            swing,
            shoulder,
            elbow[walking].mean(),
            np.percentile(knee[walking], 95),
            hips,
            lean[walking].mean(),
            at["Head"][walking, 1].mean(),
            speed[walking].mean() / motion.frame_time,
            _cadence([at["Foot_L"], at["Foot_R"]], motion.frame_time),
        ]
    )


# --------------------------------------------------------------------------- tables


def estimate(model: ExaggerationModel, motion: em.Motion, **options) -> str:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        e = exaggerate(model, motion, 2.0, lock_feet=False, **options)[1].estimate
    assert e is not None
    return f"{e.k:.2f} +- {e.uncertainty:.2f} (r {e.residual:.1f})" + (" (!)" if e.warning() else "")


def estimates_table(model: ExaggerationModel, contents: list[str]) -> list[str]:
    baseline = clip("walk-left", "normal")
    lines = [
        "| clip | before: offsets read (k as before, uncertainty as now) | after (default) "
        "| after, baseline walk-left normal = 2 |",
        "|---|---|---|---|",
    ]
    for content in contents:
        for style in STYLES:
            motion = clip(content, style)
            cells = [
                estimate(model, motion, estimate_offsets=True),
                estimate(model, motion),
                estimate(model, motion, baseline=baseline, baseline_level=2.0)
                if content != "walk-left"
                else "(the baseline's own content)",
            ]
            lines.append(f"| {content} {style} | " + " | ".join(cells) + " |")
    for content in ("run", "dash"):  # not walks: the residual and the warning should say so
        cells = [estimate(model, clip(content, "normal"), **options) for options in ({"estimate_offsets": True}, {})]
        lines.append(f"| {content} normal | " + " | ".join(cells) + " | |")
    return lines


def gait_table(model: ExaggerationModel, content: str) -> list[str]:
    normal, active = clip(content, "normal"), clip(content, "active")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before, b = exaggerate(model, normal, 3.0, estimate_offsets=True)
        after, a = exaggerate(model, normal, 3.0)
        given, _ = exaggerate(model, normal, 3.0, current=2.0)
    rows = {name: gait(m) for name, m in (("input", normal), ("before", before), ("after", after), ("given", given))}
    rows["active"] = gait(active)
    lines = [
        f"**dataset-1 {content}_normal -> 3** (k0 before {b.k0:.2f}, after {a.k0:.2f}); "
        "progress = (exaggerated - input) / (real active - input)",
        "",
        "| measure | input | before | after (default) | --from 2 | real active | progress before / after / --from 2 |",
        "|---|---|---|---|---|---|---|",
    ]
    for i, (name, _) in enumerate(MEASURES):
        gap = rows["active"][i] - rows["input"][i]
        progress = [(rows[r][i] - rows["input"][i]) / gap for r in ("before", "after", "given")]
        digits = 2 if name.startswith("cadence") else 1
        values = " | ".join(f"{rows[r][i]:.{digits}f}" for r in ("input", "before", "after", "given", "active"))
        lines.append(f"| {name} | {values} | " + " / ".join(f"{v:.2f}" for v in progress) + " |")
    return lines + [""]


def sessions_table(contents: list[str]) -> list[str]:
    """The measures on the real walks of both sessions, by intensity: which ones move the same way
    from normal to active in the training people (dataset-2, 8 takes) and in this session's actor,
    so which ones a model of the training walks can be expected to move towards this actor's."""
    folder = DATA / "Bandai-Namco-Research-Motiondataset-2/data"
    trained = {
        style: np.array([gait(em.read_bvh(folder / f"dataset-2_walk_{style}_{p:03d}.bvh")) for p in range(1, 9)])
        for style in ("exhausted", "normal", "active")
    }
    session = {content: [gait(clip(content, style)) for style in STYLES] for content in contents}
    lines = [
        "| measure | dataset-2 walks, exhausted / normal / active (mean of 8 takes) | takes whose active is "
        "above their normal | " + " | ".join(f"dataset-1 {c}, tired / normal / active" for c in contents) + " |",
        "|---|---|---|" + "---|" * len(contents),
    ]
    for i, (name, _) in enumerate(MEASURES):
        digits = 2 if name.startswith("cadence") else 1
        means = " / ".join(f"{trained[s][:, i].mean():.{digits}f}" for s in ("exhausted", "normal", "active"))
        above = int(np.sum(trained["active"][:, i] > trained["normal"][:, i]))
        ours = " | ".join(" / ".join(f"{g[i]:.{digits}f}" for g in session[c]) for c in contents)
        lines.append(f"| {name} | {means} | {above} of 8 | {ours} |")
    return lines + [""]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--development", action="store_true", help="leave out dataset-1's forward walks")
    parser.add_argument("--write", metavar="FILE.md", help="also save the tables as markdown")
    args = parser.parse_args()
    model = session_model()
    contents = list(DEVELOPMENT) + ([] if args.development else [HELD_OUT])
    lines = [
        "# Exaggeration across capture sessions",
        "",
        "Model: Bandai-Namco-Research-Motiondataset-2 walks (CC BY-NC 4.0), exhausted / normal / active = 1 / 2 / 3,",
        "takes 1-8 as people; applied to Bandai-Namco-Research-Motiondataset-1 clips (another session and actor,",
        "CC BY-NC 4.0). Produced by `PYTHONPATH=python python experiments/exaggeration_sessions.py --write",
        "experiments/EXAGGERATION_SESSIONS.md`. Tuned on",
        "walk-left, walk-right, walk-back; the forward walks (`walk`) were measured only at the end.",
        "",
        "## Estimated current intensity (k +- uncertainty (r fit residual); (!) a warning)",
        "",
        *estimates_table(model, contents),
        "",
        "## Gait of the normal walk exaggerated to 3 (no baseline), independent SciPy forward kinematics",
        "",
        "Measures: " + "; ".join(f"{n}: {d}" for n, d in MEASURES) + ".",
        "",
    ]
    for content in contents:
        lines += gait_table(model, content)
    lines += [
        "## The measures on the real walks of both sessions",
        "",
        "Where the training people and this session's actor change a measure in opposite directions from",
        "normal to active, a model of the training walks cannot move this actor's normal walk towards its",
        "active one on that measure:",
        "",
        *sessions_table(contents),
    ]
    text = "\n".join(lines)
    print(text)
    if args.write:
        atomic_write(args.write, (text + "\n").encode())


if __name__ == "__main__":
    sys.exit(main())
