"""The methods on real files of other skeletons and sources: python experiments/eval_other_sources.py

Runs the commands a user would, with no map file, on the CMU clip (subject 131 via bvh11, 31
joints, 120 fps) and the four Xia-style walks (deep-motion-editing's style-transfer results, 31
joints, the CMU database's own unit), beside a real neutral walk put on those two skeletons
(dataset-2's `walk_normal_002`, of the shipped model's test split, retargeted: the real files hold
no neutral walk):

- `decouple` and `modulate --scale 0` with the shipped model: mean activity per body part, and how
  far the expressive component moves the hands and the whole body (world positions of the file
  and of its body mechanics, from our own SciPy forward kinematics of the written numbers);
- `exaggerate --to 3` of a Xia-style walk with a model ranked on dataset-2's walks: the estimated
  intensity, and the arm swing and elbow flexion before and after;
- `mix` of a dataset-2 left-hand wave onto a Xia-style walk and onto the CMU clip: how high the
  left hand rises, and pictures.

Writes experiments/OTHER_SOURCES.md and experiments/figures/other_*.png. Data: Bandai-Namco-Research-
Motiondataset 2 (CC BY-NC 4.0); CMU Graphics Lab Motion Capture Database (via bvh11, MIT);
deep-motion-editing demo files (BSD-2).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from expressive_mocap.body import find_joint_map
from expressive_mocap.bvh import read_bvh, write_bvh
from expressive_mocap.cli import main as cli
from expressive_mocap.skeletons import retarget
from independent import read_fk

HERE = Path(__file__).resolve().parent
XIA = ("dme_demo_3d_1", "dme_demo_3d_2", "dme_comp_3d_2", "dme_demo_video_2")
PARTS = {
    "spine": ["Spine", "Chest", "Neck", "Head"],
    "arms": ["Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L", "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R"],
    "legs": ["UpperLeg_L", "LowerLeg_L", "Foot_L", "UpperLeg_R", "LowerLeg_R", "Foot_R"],
}


def run(*argv: str) -> str:
    """One command, as a user runs it; its standard output (a failure raises)."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        status = cli([str(a) for a in argv])
    if status != 0:
        raise SystemExit(f"expressive-mocap {' '.join(map(str, argv))} exited {status}")
    return out.getvalue()


def world_positions(path: Path) -> tuple[np.ndarray, list[str]]:
    """World joint positions ``[F, J, 3]`` and joint names of a BVH file, by the experiments' own
    reader and SciPy FK (:mod:`independent`)."""
    fk = read_fk(path)
    return fk.positions, fk.names


def roles_of(path: Path) -> dict:
    return find_joint_map(read_bvh(path).skeleton).joints


def conventions(path: Path) -> dict:
    """What `skeleton --json` reads of a file: its up axis, stature, ..."""
    return json.loads(run("skeleton", path, "--json"))


def stature(path: Path) -> float:
    """The standing height `skeleton` reads from the leg bones (file units): the scale here."""
    return float(conventions(path)["stature"])


def decoupled(path: Path, work: Path) -> dict:
    """Activity per body part (the model's joints) and the expressive component's reach."""
    run("decouple", path, "-o", work / "parts")
    table = np.genfromtxt(work / "parts_activity.csv", delimiter=",", names=True)
    activity = {part: float(np.mean([table[n].mean() for n in names])) for part, names in PARTS.items()}
    run("modulate", path, "--scale", "0", "-o", work / "body.bvh")
    original, _ = world_positions(path)
    body, _ = world_positions(work / "body.bvh")
    jmap, height = roles_of(path), stature(path)
    hands = [jmap[f"{s}_hand"] for s in ("left", "right")]
    moved = np.linalg.norm(original - body, axis=-1) / height
    return {**activity, "hands": float(moved[:, hands].mean(axis=0).max()), "body": float(moved.mean())}


def arm_measures(path: Path) -> tuple[float, float]:
    """Arm swing (range of the hands' travel along the walk, relative to the hips, over actor
    heights) and mean elbow flexion (degrees), averaged over both arms."""
    positions, _ = world_positions(path)
    jmap, height = roles_of(path), stature(path)
    hips = positions[:, jmap["hips"]]
    travel = hips[-1] - hips[0]
    travel[1] = 0.0
    forward = travel / max(np.linalg.norm(travel), 1e-9)
    swing, flexion = [], []
    for side in ("left", "right"):
        shoulder, elbow, wrist = (positions[:, jmap[f"{side}_{p}"]] for p in ("upper_arm", "forearm", "hand"))
        along = (wrist - hips) @ forward
        swing.append(np.ptp(along) / height)
        upper, lower = elbow - shoulder, wrist - elbow
        cosine = np.sum(upper * lower, -1) / np.linalg.norm(upper, axis=-1) / np.linalg.norm(lower, axis=-1)
        flexion.append(np.degrees(np.arccos(np.clip(cosine, -1, 1))).mean())
    return float(np.mean(swing)), float(np.mean(flexion))


def left_hand_height(path: Path) -> float:
    """How high the left hand rises above the head at its highest, over statures (negative: below)."""
    positions, _ = world_positions(path)
    jmap, read = roles_of(path), conventions(path)
    axis = "XYZ".index(read["up"][1])
    sign = 1.0 if read["up"][0] == "+" else -1.0
    rise = sign * (positions[:, jmap["left_hand"], axis] - positions[:, jmap["head"], axis])
    return float(rise.max() / read["stature"])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", default=str(Path.home() / ".cache" / "motion-data" / "dataset"))
    parser.add_argument("--other", default=str(HERE.parent.parent / "shared" / "data" / "other"))
    args = parser.parse_args()
    d2, other = Path(args.data) / "Bandai-Namco-Research-Motiondataset-2" / "data", Path(args.other)
    start = time.perf_counter()
    lines = ["# The methods on real files of other skeletons and sources", ""]
    lines.append(f"- date: {time.strftime('%Y-%m-%d %H:%M')}; command: `python experiments/eval_other_sources.py`")
    lines.append(
        "- data: CMU Graphics Lab Motion Capture Database, subject 131 (via bvh11, MIT); deep-motion-editing "
        "style-transfer demo results (BSD-2); Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0). No map file."
    )
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        walk = read_bvh(d2 / "dataset-2_walk_normal_002.bvh")  # the model's test split
        stand_ins = {}
        for name, target in (("xia", other / "dme_rest.bvh"), ("cmu", other / "cmu_scaled_131_03.bvh")):
            stand_ins[name] = work / f"neutral_on_{name}.bvh"
            write_bvh(retarget(walk, read_bvh(target), fps=30.0), stand_ins[name])
        clips = {f"{n} (Xia-style, styled walk)": other / f"{n}.bvh" for n in XIA}
        clips["cmu_scaled_131_03 (CMU, dance-like)"] = other / "cmu_scaled_131_03.bvh"
        clips["dataset-2 neutral walk on the Xia skeleton"] = stand_ins["xia"]
        clips["dataset-2 neutral walk on the CMU skeleton"] = stand_ins["cmu"]
        lines += ["", "## Decoupling with the shipped model", ""]
        lines.append(
            "Mean activity per body part (0: body mechanics, 1: expressive) and how far the expressive "
            "component moves the body: mean displacement between the file and its body mechanics "
            "(`modulate --scale 0`), over statures (standing height from the leg bones), for the hand that moves more "
            "and for every joint."
        )
        lines += ["", "| file | spine | arms | legs | hand moved | body moved |", "|---|---|---|---|---|---|"]
        for label, path in clips.items():
            r = decoupled(path, work)
            lines.append(
                f"| {label} | {r['spine']:.2f} | {r['arms']:.2f} | {r['legs']:.2f} "
                f"| {r['hands']:.3f} | {r['body']:.3f} |"
            )
        lines += ["", "## Exaggeration with a model of Bandai-Namco walks", ""]
        argv = []
        for level, style in enumerate(("exhausted", "normal", "active"), 1):
            argv += ["--level", str(level), *[d2 / f"dataset-2_walk_{style}_{p:03d}.bvh" for p in range(1, 9)]]
        run("rank", *argv, "-o", work / "walks.npz")
        lines += ["| walk | estimated intensity | arm swing before -> after | elbow flexion before -> after |"]
        lines += ["|---|---|---|---|"]
        for name in (*XIA, "neutral_on_xia"):
            path = stand_ins["xia"] if name == "neutral_on_xia" else other / f"{name}.bvh"
            out = run("exaggerate", "--model", work / "walks.npz", "--input", path, "--to", "3", "-o", work / "ex.bvh")
            estimate = next((line.strip() for line in out.splitlines() if "estimated" in line), "?")
            (s0, f0), (s1, f1) = arm_measures(path), arm_measures(work / "ex.bvh")
            lines.append(f"| {name} | {estimate} | {s0:.3f} -> {s1:.3f} | {f0:.0f} -> {f1:.0f} deg |")
        lines += ["", "## A Bandai-Namco wave mixed onto their walks", ""]
        wave = d2 / "dataset-2_wave-left-hand_normal_001.bvh"
        lines += ["| body | left hand above the head, before -> after (statures) |", "|---|---|"]
        for name, path in (("dme_comp_3d_2", other / "dme_comp_3d_2.bvh"), ("cmu", other / "cmu_scaled_131_03.bvh")):
            run("mix", "--body", path, "--expressive", wave, "-o", work / f"mix_{name}.bvh")
            lines.append(
                f"| {name} | {left_hand_height(path):.3f} -> {left_hand_height(work / f'mix_{name}.bvh'):.3f} |"
            )
        figures = HERE / "figures"
        run("render", other / "dme_comp_3d_2.bvh", "--decoupled", "--poses", "5", "-o", figures / "other_decoupled.png")
        run("render", other / "dme_comp_3d_2.bvh", work / "mix_dme_comp_3d_2.bvh", "--poses", "5",
            "-o", figures / "other_mix.png")  # fmt: skip
    lines += ["", f"(took {time.perf_counter() - start:.0f} s)", ""]
    (HERE / "OTHER_SOURCES.md").write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
