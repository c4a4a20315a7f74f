"""How much neutral locomotion a useful body-mechanics model needs: test MSE against the number of
training clips. python experiments/neutral_data_needed.py [--max-iter N] [--sizes 2,4,...]

Dataset-2's 145 neutral locomotion clips (walk, walk-turn-left/right, run; style normal) are split
once by clip (seed 0, 30% of the frames held out); models are trained with
`train_body_model` (its own 70/30 split inside the clips given, no unlabelled clips) on the first n of
the remaining clips, shuffled with a fixed seed, and every model is scored on the same held-out
clips: pose MSE of the network and of the mean training pose (the baseline a model must beat).
Writes experiments/NEUTRAL_DATA.md. Data: Bandai-Namco-Research-Motiondataset-2, CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import subprocess
import time
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling.body_model import pose_vectors
from expressive_mocap.decoupling.training import split_by_group, train_body_model

HERE = Path(__file__).resolve().parent
SHARED = HERE.parent.parent / "shared" / "data"
STYLES = ("walk", "walk-turn-left", "walk-turn-right", "run")


def neutral_clips() -> list[Path]:
    dataset = Path(
        subprocess.run(
            [str(SHARED / "unpack"), str(Path.home() / ".cache" / "motion-data")],
            capture_output=True,
            text=True,
            check=True,
        )
        .stdout.strip()
        .splitlines()[-1]
    )
    folder = dataset / "Bandai-Namco-Research-Motiondataset-2" / "data"
    return sorted(p for s in STYLES for p in folder.glob(f"dataset-2_{s}_normal_*.bvh"))


def held_out_mse(model, training, motions) -> tuple[float, float]:
    """Pose MSE on ``motions`` of the model's network and of the mean pose of its ``training`` clips."""

    def vectors(clips, pick):
        return np.concatenate([pose_vectors(pick(m), model.predicted, model.hemispheres) for m in clips])

    actual = vectors(motions, lambda m: m.rotations)
    mean_pose = vectors(training, lambda m: m.rotations).mean(axis=0)
    return float(np.mean((vectors(motions, model.predict) - actual) ** 2)), float(np.mean((actual - mean_pose) ** 2))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-iter", type=int, default=150)
    parser.add_argument("--sizes", default="2,4,8,16,32,64,99")
    args = parser.parse_args()
    paths = neutral_clips()
    motions = [em.read_bvh(p) for p in paths]
    groups = np.concatenate([np.full(m.n_frames, k) for k, m in enumerate(motions)])
    train_rows, test_rows = split_by_group(groups, 0.3, 0)
    train_ids, test_ids = np.unique(groups[train_rows]), np.unique(groups[test_rows])
    order = np.random.default_rng(1).permutation(train_ids)
    test = [motions[k] for k in test_ids]
    rows = []
    for n in [int(s) for s in args.sizes.split(",")]:
        chosen = [motions[k] for k in order[:n]]
        start = time.perf_counter()
        model = train_body_model(chosen, max_iter=args.max_iter, log=None)
        seconds = time.perf_counter() - start
        network, baseline = held_out_mse(model, chosen, test)
        rows.append((n, sum(m.n_frames for m in chosen), network, baseline, seconds))
        print(
            f"{n} clips: held-out MSE {network:.3g} (mean pose {baseline:.3g}, "
            f"ratio {network / baseline:.2f}) in {seconds:.0f} s",
            flush=True,
        )
    lines = [
        "# How much neutral data a body-mechanics model needs",
        "",
        f"`python experiments/neutral_data_needed.py --max-iter {args.max_iter} --sizes {args.sizes}`"
        f" ({time.strftime('%Y-%m-%d')}). Data: Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0),",
        f"its {len(paths)} neutral locomotion clips; {len(test)} held "
        "out (30% of the frames by clip, seed 0), models trained",
        "on the first n of the others (no unlabelled clips), every model scored on the same held-out clips.",
        "",
        "| training clips | frames | held-out MSE | mean-pose MSE | ratio | seconds |",
        "|---|---|---|---|---|---|",
        *[
            f"| {n} | {frames:,} | {net:.3g} | {base:.3g} | {net / base:.2f} | {s:.0f} |"
            for n, frames, net, base, s in rows
        ],
        "",
    ]
    (HERE / "NEUTRAL_DATA.md").write_text("\n".join(lines))


if __name__ == "__main__":
    main()
