"""What edits do to the feet of walks of other rigs, measured on the files the commands write.

    python experiments/eval_edits_other_rigs.py [--other DIR] [--data DIR] [--out FILE]

Each walk of ``DIR`` (the shared folder of files on other rigs) is edited with the command line,
as a user would: ``exaggerate`` to 0, 1, 3 and 4 with a model of dataset-2's walks (takes 1-8 of
exhausted, normal and active walks as 8 people at intensities 1-3; trained here; ``--no-timing``
so the output is frame for frame with the input), ``modulate --scale`` 0 and 2, ``decouple``
(its body-mechanics file) and ``mix`` (the walk's body mechanics with a dataset-2 gesture). On the
file written, with this folder's own BVH reader and SciPy forward kinematics (:mod:`independent`),
through the input's contacts (the package's detector on the input, Y up):

- stance-foot speed: per contact, the mean horizontal speed of the ankle and the toe joint over
  its frames, output over input (a contact whose input speed is under 2 % of the actor height a
  second is measured against that: a still foot's own speed is noise); the median and the worst
  contact;
- feet turned: the angle between the input's and the output's foot world rotation, mean over the
  stance frames;
- below the input's feet: how far the output's lowest ankle or toe joint goes below the input's in
  the same stance frame, in % of the actor height;
- the edit itself: the largest turn of any joint from the input, mean over the frames (degrees).

Data: Bandai-Namco-Research-Motiondataset (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database; deep-motion-editing demo files (BSD-2); the 21-joint walks of the shared folder.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.body.contacts import contact_intervals, foot_contacts
from expressive_mocap.body.conventions import read_conventions, upright
from expressive_mocap.rotations import quat
from independent import read_fk
from setting import arguments, bandai_dir, run, walks_model

WALKS = ("m21_walk", "m21_female-walk", "cmu_scaled_131_03", "cmu_01_01", "dme_comp_3d_2")
STILL = 0.02  # x actor height per second: a stance foot slower than this is still
GESTURE = "dataset-2_wave-left-hand_normal_001.bvh"


def edits(walk: Path, model: Path, gesture: Path, work: Path) -> dict[str, Path]:
    """Edit name -> the file the command wrote."""
    out = {}
    for to in (0, 1, 3, 4):
        out[f"exaggerate --to {to}"] = work / f"exaggerate_{to}.bvh"
        run(
            "exaggerate",
            "--model",
            model,
            "--input",
            walk,
            "--to",
            to,
            "--no-timing",
            "-o",
            out[f"exaggerate --to {to}"],
        )
    for scale in (0, 2):
        out[f"modulate --scale {scale}"] = work / f"modulate_{scale}.bvh"
        run("modulate", walk, "--scale", scale, "-o", out[f"modulate --scale {scale}"])
    run("decouple", walk, "-o", work / "parts")
    out["decouple (body)"] = work / "parts_body.bvh"
    out["mix (a gesture on it)"] = work / "mix.bvh"
    run("mix", "--body", walk, "--expressive", gesture, "-o", out["mix (a gesture on it)"])
    return out


def _speed(points: np.ndarray, frame_time: float) -> float:
    """Mean horizontal speed of ``points [F, N, 3]`` (Y up)."""
    return float(np.linalg.norm(np.diff(points[..., [0, 2]], axis=0), axis=-1).mean() / frame_time)


def measure(walk: Path, edited: Path) -> tuple[float, float, float, float, float]:
    """(median and worst per-contact stance speed ratio, mean feet turn in degrees, deepest the
    output's feet go below the input's in the same stance frame in % of the actor height, and
    the edit itself: the mean over frames of the largest joint turn, degrees)."""
    motion = em.read_bvh(walk)
    jmap = em.Body.of(motion.skeleton).joint_map
    height = em.actor_height(motion.skeleton)
    turn = read_conventions(motion, jmap).rotation()
    contacts = foot_contacts(upright(motion))
    a, b = read_fk(walk), read_fk(edited)
    pa, pb = quat.rotate(turn, a.positions), quat.rotate(turn, b.positions)
    ratios, turns, below = [], [], []
    for s, side in enumerate(("left", "right")):
        joints = [jmap[f"{side}_foot"], jmap[f"{side}_toes"]]
        for interval in contact_intervals(contacts[:, s], motion.frame_time):
            if interval.end - interval.start < 2:
                continue
            frames = slice(interval.start, interval.end + 1)
            before, after = (_speed(p[frames][:, joints], motion.frame_time) for p in (pa, pb))
            ratios.append(after / max(before, STILL * height))
        stance = contacts[:, s]
        ra, rb = a.rotations[jmap[f"{side}_foot"]], b.rotations[jmap[f"{side}_foot"]]
        turns.append(np.degrees((ra[stance].inv() * rb[stance]).magnitude()))
        below.append(pa[stance][:, joints, 1].min(axis=1) - pb[stance][:, joints, 1].min(axis=1))
    edit = np.max([np.degrees((ra.inv() * rb).magnitude()) for ra, rb in zip(a.rotations, b.rotations)], axis=0)
    return (
        float(np.median(ratios)),
        float(np.max(ratios)),
        float(np.concatenate(turns).mean()),
        float(max(0.0, np.concatenate(below).max()) * 100 / height),
        float(edit.mean()),
    )


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        model = work / "walks.npz"
        walks_model(dataset).save(model)
        print(
            "| walk | edit | edit: largest joint turn (deg, mean) | stance speed, median / worst contact (x input) "
            "| feet turned (deg) | below the input's feet (%) |"
        )
        print("|---|---|---|---|---|---|")
        for name in WALKS:
            walk = args.other / f"{name}.bvh"
            for edit, path in edits(walk, model, dataset / GESTURE, work).items():
                median, worst, turned, below, change = measure(walk, path)
                row = f"| {name} | {edit} | {change:.1f} | {median:.2f} / {worst:.2f} | {turned:.1f} | {below:.2f} |"
                print(row, flush=True)


if __name__ == "__main__":
    main()
