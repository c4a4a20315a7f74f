"""Does an uncalibrated neutral walk read as neutral on any rig? Mean activity of the `decouple`
command (uncalibrated, the shipped model) on neutral walks of other rigs, beside the training
session's own neutral walks.

    python experiments/eval_baseline.py [--other DIR] [--data DIR]

Rows: dataset-2's held-out neutral walks (the model's test clips of `walk_normal`: takes 2, 3, 6,
12, 14, 17, 24) on the Bandai-Namco rig;
the same walks retargeted (`retarget --to`) onto each synthetic rig and each real rig of the
shared folder, decoupled there; and the shared folder's own neutral walks (`m21_walk`,
`m21_female-walk`). Activity: the mean over frames and over the model's 20 predicted joints, and
over spine and chest (the trunk), read from the `_activity.csv` the command writes.

Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database; the 21-joint walks of the shared folder (Semi-Motion-Style-Transfer, MIT).
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from setting import REPO, arguments, bandai_dir, described, rig_targets, run

TAKES = (2, 3, 6, 12, 14, 17, 24)  # the shipped model's held-out walks (its training split)


def activity(path: Path, work: Path) -> tuple[float, float]:
    """Mean activity (all predicted joints, trunk) of `decouple PATH`."""
    run("decouple", path, "-o", work / "out")
    table = np.genfromtxt(work / "out_activity.csv", delimiter=",", names=True)
    names = table.dtype.names
    values = np.column_stack([table[n] for n in names])
    predicted = [k for k, n in enumerate(names) if n not in ("joint_Root", "Hips")]
    trunk = [names.index("Spine"), names.index("Chest")]
    return float(values[:, predicted].mean()), float(values[:, trunk].mean())


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    walks = [dataset / f"dataset-2_walk_normal_{k:03d}.bvh" for k in TAKES]
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        found = [activity(w, work) for w in walks]
        rows.append(("dataset-2 neutral walks, Bandai-Namco rig", found))
        for rig, target in rig_targets(args.other, work).items():
            on_rig = []
            for k, walk in enumerate(walks):
                moved = work / f"{rig}_{k}.bvh"
                run("retarget", walk, "--to", target, "-o", moved)
                on_rig.append(activity(moved, work))
            rows.append((f"the same walks retargeted to {rig}", on_rig))
            print(rig, flush=True)
        for name in ("m21_walk", "m21_female-walk"):
            own = [activity(args.other / f"{name}.bvh", work)]
            rows.append((f"{name} (the shared folder's own neutral walk)", own))
    base = np.mean([a for a, _ in rows[0][1]])
    lines = [
        "# Uncalibrated neutral walks on any rig",
        "",
        described(__doc__),
        "",
        "`python experiments/eval_baseline.py`. Data: " + __doc__.rsplit("Data: ", 1)[1].strip().replace("\n", " "),
        "",
        "| walks | n | mean activity | minus the training session's | trunk activity |",
        "|---|---|---|---|---|",
    ]
    for label, found in rows:
        mean = np.mean([a for a, _ in found])
        trunk = np.mean([t for _, t in found])
        lines.append(f"| {label} | {len(found)} | {mean:.3f} | {mean - base:+.3f} | {trunk:.3f} |")
    (REPO / "experiments" / "BASELINE.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))


if __name__ == "__main__":
    main()
