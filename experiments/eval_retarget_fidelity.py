"""What a viewer sees of walks of other rigs retargeted onto the canonical (Bandai-Namco) body:
stance feet, the trunk's lines, and a round trip's height.

    python experiments/eval_retarget_fidelity.py [--other DIR] [--data DIR]

For each walk of ``DIR`` (the shared folder of files on other rigs), retargeted with
``onto_canonical(plant_feet=False)``, through the source's own contacts:
- the stance ankle and toe joint heights (cm) and the foot's pitch (degrees, ankle to toe joint
  against the floor), beside a dataset-2 walk's own (``dataset-2_walk_normal_001``);
- the mean and largest angle between the source's and the retarget's hips-to-chest and
  chest-to-head lines, each in its frame's heading frame;
- the height of a round trip A -> Bandai -> A against A, in % of A's actor height;
- the stance feet's horizontal speed (ankle and toe joints, over pairs of frames the source has
  the foot down) of the default retarget (feet planted), in actor heights a second, over the
  source's.
Positions by forward kinematics; every measure is computed here, not by the package's reports.
Prints the table; the recorded runs, before and after, are in experiments/RETARGET_FIDELITY.md.
Data: Bandai-Namco-Research-Motiondataset (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database; deep-motion-editing demo files (BSD-2).
"""

from __future__ import annotations

import numpy as np

import expressive_mocap as em
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.conventions import read_conventions, upright
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.canonical import onto_canonical
from expressive_mocap.skeletons.retargeting import retarget
from setting import arguments, bandai_dir

WALKS = ("m21_walk", "m21_female-walk", "cmu_scaled_131_03", "cmu_01_01", "dme_comp_3d_2")


def canonical_points(motion: em.Motion) -> tuple[np.ndarray, dict]:
    jmap = find_joint_map(motion.skeleton)
    return quat.rotate(read_conventions(motion, jmap).rotation(), motion.positions()), jmap


def stance(motion: em.Motion, contacts: np.ndarray) -> tuple[float, float, float]:
    points, jmap = canonical_points(motion)
    rows = []
    for s, side in enumerate(("left", "right")):
        ankle, toe = points[:, jmap[f"{side}_foot"]], points[:, jmap[f"{side}_toes"]]
        line = toe - ankle
        pitch = np.degrees(np.arctan2(line[:, 1], np.linalg.norm(line[:, [0, 2]], axis=1)))
        rows.append((ankle[contacts[:, s], 1].mean(), toe[contacts[:, s], 1].mean(), pitch[contacts[:, s]].mean()))
    ankle, toe, pitch = np.mean(rows, axis=0)
    return float(ankle), float(toe), float(pitch)


def stance_speed(motion: em.Motion, contacts: np.ndarray) -> float:
    points, jmap = canonical_points(motion)
    steps = []
    for s, side in enumerate(("left", "right")):
        both = contacts[1:, s] & contacts[:-1, s]
        for part in ("foot", "toes"):
            moved = np.diff(points[:, jmap[f"{side}_{part}"]][:, [0, 2]], axis=0)
            steps.append(np.linalg.norm(moved, axis=1)[both])
    height = read_conventions(motion, jmap).height
    return float(np.concatenate(steps).mean() * motion.fps / height)


def trunk(motion: em.Motion) -> list[np.ndarray]:
    points, jmap = canonical_points(motion)
    left = points[:, jmap["left_upper_leg"]] - points[:, jmap["right_upper_leg"]]
    turn = quat.about("Y", -np.degrees(np.arctan2(-left[:, 2], left[:, 0])))
    lines = []
    for a, b in (("hips", "chest"), ("chest", "head")):
        line = quat.rotate(turn, points[:, jmap[b]] - points[:, jmap[a]])
        lines.append(line / np.linalg.norm(line, axis=-1, keepdims=True))
    return lines


def apart(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))


def main() -> None:
    args = arguments(__doc__)
    bandai = em.read_bvh(bandai_dir(args.data) / "dataset-2_walk_normal_001.bvh")
    own = stance(bandai, foot_contacts(bandai))
    print(f"dataset-2 walk: stance ankle {own[0]:.1f} cm, toe {own[1]:.1f} cm, pitch {own[2]:.1f} deg")
    print(
        "| walk | ankle cm | toe cm | pitch deg | hips-chest deg (mean/max) | chest-head deg | round trip % "
        "| stance speed x source |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in WALKS:
        source = em.read_bvh(args.other / f"{name}.bvh")
        out, _ = onto_canonical(source, plant_feet=False)
        ankle, toe, pitch = stance(out, foot_contacts(upright(source)))
        lines = [apart(m, t) for m, t in zip(trunk(out), trunk(source))]
        back = retarget(retarget(source, bandai, plant_feet=False), source, plant_feet=False)
        jmap = find_joint_map(source.skeleton)
        conventions = read_conventions(source, jmap)
        up = quat.rotate(quat.conjugate(conventions.rotation()), np.array([0.0, 1.0, 0.0]))
        lift = (back.positions() - source.positions()) @ up
        trip = 100 * np.abs(lift).mean() / conventions.height
        contacts = foot_contacts(upright(source))
        sliding = stance_speed(onto_canonical(source)[0], contacts) / stance_speed(source, contacts)
        print(
            f"| {name} | {ankle:.1f} | {toe:.1f} | {pitch:.1f} | {lines[0].mean():.1f} / {lines[0].max():.1f} "
            f"| {lines[1].mean():.1f} / {lines[1].max():.1f} | {trip:.2f} | {sliding:.2f} |"
        )


if __name__ == "__main__":
    main()
