"""Do edits commute with retargeting? E(R(x)) against R(E(x)), on the files the commands write.

    python experiments/eval_commutation.py [--other DIR] [--data DIR]

``x`` is a dataset-2 wave (``wave-left-hand_normal_001``: decoupling a neutral walk changes little)
or walk (``walk_normal_010``: exaggeration; ``mix`` takes the walk's body and the wave's expression),
``R`` the retarget onto another rig (``retarget --target``: each synthetic rig's walk, and each
walk of ``DIR``, the shared folder of files on other rigs), ``E`` one edit as a user runs it:
``decouple`` (its body-mechanics file), ``modulate --scale`` 0 and 2, ``mix`` (the walk's body
mechanics with the wave's expressiveness) and ``exaggerate --to 3`` with a model of dataset-2's
walks (takes 1-8 of exhausted, normal and active as 8 people at intensities 1-3, trained here;
``--no-timing``). E(R(x)): the retargeted walk edited on its rig; R(E(x)): the edit made on the
Bandai-Namco walk, then retargeted. Both files are read with this folder's own BVH reader and
SciPy forward kinematics (:mod:`independent`); the figure is each frame's mean joint distance
between the two, in % of the rig's actor height: the mean over frames and the worst frame (in
brackets, the edit's own size: the same distance between E(R(x)) and R(x)). The rigs of the shared
folder's walks ``dme_*`` are ``cmu_01_01``'s skeleton.

Data: Bandai-Namco-Research-Motiondataset (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database; deep-motion-editing demo files (BSD-2); the 21-joint walks of the shared folder.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.body.jointmap import find_joint_map
from independent import read_fk
from setting import arguments, bandai_dir, rig_targets, run, walks_model

WALK, WAVE = "dataset-2_walk_normal_010.bvh", "dataset-2_wave-left-hand_normal_001.bvh"


def edit(name: str, walk: Path, wave: Path, model: Path, out: Path) -> Path:
    """``out`` written by edit ``name`` of the ``walk`` or ``wave`` (one rig's)."""
    if name == "decouple":
        run("decouple", wave, "-o", out.with_suffix(""))
        return out.with_name(out.stem + "_body.bvh")
    if name.startswith("modulate"):
        run("modulate", wave, "--scale", name.split()[-1], "-o", out)
    elif name == "mix":
        run("mix", "--body", walk, "--expressive", wave, "-o", out)
    else:
        run("exaggerate", "--model", model, "--input", walk, "--to", 3, "--no-timing", "-o", out)
    return out


def edited_clip(name: str, walk: Path, wave: Path) -> Path:
    """The clip edit ``name`` starts from (the body source of ``mix``)."""
    return wave if name == "decouple" or name.startswith("modulate") else walk


EDITS = ("decouple", "modulate 0", "modulate 2", "mix", "exaggerate 3")


def apart(a: Path, b: Path, height: float) -> tuple[float, float]:
    """(mean, worst frame) of the mean joint distance between two files of one skeleton, % of height."""
    pa, pb = read_fk(a).positions, read_fk(b).positions
    frames = min(len(pa), len(pb))
    per_frame = np.linalg.norm(pa[:frames] - pb[:frames], axis=-1).mean(axis=1) / height * 100
    return float(per_frame.mean()), float(per_frame.max())


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        model = work / "walks.npz"
        walks_model(dataset).save(model)
        targets = rig_targets(args.other, work)
        walk, wave = dataset / WALK, dataset / WAVE
        edited = {e: edit(e, walk, wave, model, work / f"bandai_{e.replace(' ', '_')}.bvh") for e in EDITS}
        print("| rig | " + " | ".join(EDITS) + " |")
        print("|---|" + "---|" * len(EDITS))
        for rig, target in targets.items():
            on_rig, wave_on_rig = work / f"{rig}_walk.bvh", work / f"{rig}_wave.bvh"
            run("retarget", walk, "--to", target, "-o", on_rig)
            run("retarget", wave, "--to", target, "-o", wave_on_rig)
            skeleton = em.read_bvh(on_rig).skeleton
            height = read_conventions(em.read_bvh(on_rig), find_joint_map(skeleton)).height
            cells = []
            for e in EDITS:
                after = edit(e, on_rig, wave_on_rig, model, work / f"{rig}_{e.replace(' ', '_')}.bvh")  # E(R(x))
                before = work / f"{rig}_{e.replace(' ', '_')}_R.bvh"
                run("retarget", edited[e], "--to", target, "-o", before)  # R(E(x))
                mean, worst = apart(after, before, height)
                size, _ = apart(after, edited_clip(e, on_rig, wave_on_rig), height)
                cells.append(f"{mean:.2f} / {worst:.2f} ({size:.1f})")
            print(f"| {rig} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
