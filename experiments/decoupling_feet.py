"""Stance feet after the decoupling edits: python experiments/decoupling_feet.py [--data DIR] [--figure]

Every edit runs through the package (shipped body model, no calibration), is written to a BVH
file and read back by this script's own parser and SciPy forward kinematics (never the
package's). A foot is in stance where the body-mechanics source has it on the floor: its ankle
or toe within 5 cm of that joint's lowest height in the clip (5th percentile) and moving slower
than 50 cm/s across the floor, measured on the source the same independent way. The figure is
the mean horizontal speed of the ankles and toes (cm/s) between two consecutive stance frames,
in the edit and in its body-mechanics source:

- ``modulate --scale 0`` and ``--scale 2`` of every clip (source: the clip);
- ``mix``: each walk with each gesture of the same style, both ways (source: ``--body``), and
  ``mix walks``: each walk with the next style's walk;
- ``blend``: each walk into each gesture of the same style and back, body window 30:40 and
  expressive window 150:160, and the other way round (in between, one clip's expression rides on
  the other's body; source: the naive blend, whole poses over the body window: its feet are the
  first clip's before the window and the second's after it);

each with the feet locked (the default) and without (``--no-foot-lock``), with the default
``--joints`` and with ``--joints all``. The ratio is the edit's stance speed over its source's,
per edit; the table gives the mean and the largest.

Clips: dataset-2 walks and the wave-right-hand and raise-up-left-hand gestures, take 001 of each
of the seven styles; dataset-1 walks and the bye, byebye and guide gestures in every style (take 001).
Data: Bandai-Namco-Research-Motiondataset 1 and 2 (Bandai Namco Research Inc., 2022;
Kobayashi et al., arXiv:2306.08861), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling import BodyModel
from expressive_mocap.decoupling.edits import blend, mix, modulate
from independent import read_fk

HERE = Path(__file__).resolve().parent
DATA = Path.home() / ".cache/motion-data/dataset"
STYLES_2 = ("normal", "active", "elderly", "exhausted", "feminine", "masculine", "youthful")
GESTURES_2 = ("wave-right-hand", "raise-up-left-hand")
GESTURES_1 = ("bye", "byebye", "guide")
FEET = ("Foot_L", "Toes_L", "Foot_R", "Toes_R")
STANCE_CM = 5.0
STANCE_SPEED = 50.0  # cm/s
WINDOWS = (((30, 40), (150, 160)), ((150, 160), (30, 40)))  # (body, expressive) windows


def read_positions(path: Path) -> tuple[list[str], np.ndarray, float]:
    """Joint names, world positions ``[F, J, 3]`` and frame time of a BVH file: own parser, SciPy FK."""
    fk = read_fk(path)
    return fk.names, fk.positions, fk.frame_time


def stance(names: list[str], pos: np.ndarray, frame_time: float) -> np.ndarray:
    """``bool [F, 4]``: per joint of :data:`FEET`, the frames its foot is down: the ankle or the toe
    within :data:`STANCE_CM` of that joint's floor (its 5th percentile height) and moving slower
    than :data:`STANCE_SPEED` across the floor."""
    p = pos[:, [names.index(n) for n in FEET]]
    low = p[:, :, 1] - np.percentile(p[:, :, 1], 5, axis=0) < STANCE_CM
    slow = np.linalg.norm(np.gradient(p[:, :, [0, 2]], axis=0), axis=-1) / frame_time < STANCE_SPEED
    down = low & slow
    return np.repeat(down[:, 0::2] | down[:, 1::2], 2, axis=1)


def fastest(names: list[str], pos: np.ndarray, frame_time: float) -> float:
    """The largest horizontal speed of an ankle or toe (cm/s): a correction spread over the swing
    must not make the swinging foot jump."""
    p = pos[:, [names.index(n) for n in FEET]][:, :, [0, 2]]
    return float((np.linalg.norm(np.diff(p, axis=0), axis=-1) / frame_time).max())


def stance_speed(names: list[str], pos: np.ndarray, frame_time: float, down: np.ndarray) -> float:
    """Mean horizontal speed (cm/s) of the feet joints between two consecutive ``down`` frames."""
    p = pos[:, [names.index(n) for n in FEET]][:, :, [0, 2]]
    speed = np.linalg.norm(np.diff(p, axis=0), axis=-1) / frame_time
    both = down[1:] & down[:-1]
    return float(speed[both].mean()) if both.any() else 0.0


def measured(motion: em.Motion, folder: Path, name: str):
    path = folder / f"{name}.bvh"
    em.write_bvh(motion, path)
    return read_positions(path)


def clips(data: Path) -> dict[str, tuple[list[Path], list[Path]]]:
    """Per set: (walks, gestures) of the same styles, in style order."""
    d2, d1 = data / "Bandai-Namco-Research-Motiondataset-2/data", data / "Bandai-Namco-Research-Motiondataset-1/data"
    sets = {}
    sets["dataset-2"] = (
        [d2 / f"dataset-2_walk_{s}_001.bvh" for s in STYLES_2],
        [d2 / f"dataset-2_{g}_{s}_001.bvh" for s in STYLES_2 for g in GESTURES_2],
    )
    styles_1 = sorted(p.name.split("_")[2] for p in d1.glob("dataset-1_walk_*_001.bvh"))
    sets["dataset-1"] = (
        [d1 / f"dataset-1_walk_{s}_001.bvh" for s in styles_1],
        [d1 / f"dataset-1_{g}_{s}_001.bvh" for s in styles_1 for g in GESTURES_1],
    )
    return sets


def edits(walks: list[Path], gestures: list[Path]):
    """(kind, source motion, edit(plant_feet, joints) -> motion) for every edit of the set."""
    read = {p: em.read_bvh(p) for p in walks + gestures}
    per_style = len(gestures) // len(walks)
    out = []
    for motion in read.values():
        for scale in (0.0, 2.0):
            out.append(
                (f"modulate {scale:g}", motion, lambda pf, j, m=motion, s=scale: modulate(m, s, MODEL, plant_feet=pf))
            )
    for k, walk in enumerate(walks):
        for gesture in gestures[k * per_style : (k + 1) * per_style]:
            for a, b in ((read[walk], read[gesture]), (read[gesture], read[walk])):
                out.append(("mix", a, lambda pf, j, a=a, b=b: mix(a, b, MODEL, joints=j, plant_feet=pf)))
                for w in WINDOWS:
                    naive = blend(a, b, None, *w)
                    out.append(
                        ("blend", naive, lambda pf, j, a=a, b=b, w=w: blend(a, b, MODEL, *w, joints=j, plant_feet=pf))
                    )
    for a, b in zip(walks, walks[1:] + walks[:1]):  # a walk with the next style's walk: every joint by default
        out.append(
            ("mix walks", read[a], lambda pf, j, a=read[a], b=read[b]: mix(a, b, MODEL, joints=j, plant_feet=pf))
        )
    return out


def run(data: Path, folder: Path) -> list[str]:
    rows = []
    for name, (walks, gestures) in clips(data).items():
        results: dict[tuple[str, bool, str], list[tuple[float, float]]] = {}
        for n, (kind, source, edit) in enumerate(edits(walks, gestures)):
            names, pos, ft = measured(source, folder, f"source{n}")
            down = stance(names, pos, ft)
            base, top = stance_speed(names, pos, ft, down), fastest(names, pos, ft)
            for plant in (True, False):
                for joints in [None] if kind.startswith("modulate") else [None, "all"]:
                    _, out_pos, _ = measured(edit(plant, joints), folder, "edit")
                    speed, peak = stance_speed(names, out_pos, ft, down), fastest(names, out_pos, ft)
                    results.setdefault((kind, plant, joints or "default"), []).append((base, speed, peak / top))
        for (kind, plant, joints), pairs in results.items():
            base, speed, peak = np.array(pairs).T
            ratio = speed / np.maximum(base, 1e-9)
            rows.append(
                f"| {name} | {kind} | {joints} | {'locked' if plant else 'not locked'} | {len(pairs)} | "
                f"{base.mean():.1f} | {speed.mean():.1f} | {ratio.mean():.2f} | {ratio.max():.2f} | {peak.max():.2f} |"
            )
            print(rows[-1], flush=True)
    return rows


def figure(data: Path, folder: Path, out: Path) -> None:
    """The left ankle's horizontal speed through a dataset-1 old walk and its body mechanics
    (``modulate --scale 0``), locked and not, stance frames shaded."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    path = data / "Bandai-Namco-Research-Motiondataset-1/data/dataset-1_walk_old_001.bvh"
    motion = em.read_bvh(path)
    names, pos, ft = measured(motion, folder, "input")
    down = stance(names, pos, ft)[:, 0]
    j = names.index("Foot_L")
    fig, ax = plt.subplots(figsize=(9, 3.2))
    t = np.arange(len(pos) - 1) * ft
    for label, m in (
        ("input (old walk)", motion),
        ("--scale 0, feet not locked", modulate(motion, 0.0, MODEL, plant_feet=False)),
        ("--scale 0 (feet locked: default)", modulate(motion, 0.0, MODEL)),
    ):
        _, p, _ = measured(m, folder, "edit")
        ax.plot(t, np.linalg.norm(np.diff(p[:, j, [0, 2]], axis=0), axis=-1) / ft, label=label, lw=1.2)
    ax.fill_between(
        t, 0, 1, where=down[1:] & down[:-1], transform=ax.get_xaxis_transform(), color="0.9", label="stance"
    )
    ax.set_xlabel("seconds")
    ax.set_ylabel("left ankle speed (cm/s)")
    ax.set_ylim(0, 400)
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title("modulate --scale 0 of dataset-1_walk_old_001 (Bandai-Namco, CC BY-NC 4.0)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    print(f"wrote {out}")


MODEL = BodyModel.load()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", type=Path, default=DATA)
    parser.add_argument("--figure", action="store_true", help="also draw experiments/figures/feet_modulate.png")
    parser.add_argument("--out", type=Path, default=HERE / "FEET.md")
    args = parser.parse_args()
    start = time.time()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        if args.figure:
            figure(args.data, folder, HERE / "figures" / "feet_modulate.png")
        rows = run(args.data, folder)
    header = [
        "# Stance feet after the decoupling edits",
        "",
        "`python experiments/decoupling_feet.py` (how it measures: its docstring). Stance-foot speed: mean horizontal",
        "speed of the ankles and toes (cm/s) over the frames where the body-mechanics source has the foot down,",
        "measured with an independent BVH reader and SciPy forward kinematics. Ratio: edit / source, per edit.",
        "Fastest foot: the edit's largest ankle or toe speed over the source's (any frame), the largest of the set.",
        "Bandai-Namco-Research-Motiondataset 1 and 2, CC BY-NC 4.0.",
        "",
        "| set | edit | joints | feet | edits | source cm/s | edit cm/s | mean ratio | largest ratio | fastest foot |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    args.out.write_text("\n".join(header + rows) + f"\n\n({time.time() - start:.0f} s)\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
