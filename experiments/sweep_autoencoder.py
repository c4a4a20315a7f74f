"""Autoencoder MSE against hidden size (the paper's 300/150/50/15) on the shipped model's data:
python experiments/sweep_autoencoder.py [--data DIR] [--max-iter N]

Poses of the dataset-2 neutral locomotion clips (the shipped model's training set, its
representation and its 70/30 split by clip). Data: Bandai-Namco-Research-Motiondataset-2,
CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import expressive_mocap as em
from eval_decoupling import NEUTRAL_CONTENTS, dataset_root
from expressive_mocap.decoupling.body_model import BodyModel, pose_vectors
from expressive_mocap.decoupling.training import sweep_autoencoder

HERE = Path(__file__).resolve().parent


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", help="folder holding Bandai-Namco-Research-Motiondataset-2")
    parser.add_argument(
        "--max-iter", type=int, default=300, help="L-BFGS iterations (default 300, as the shipped model)"
    )
    args = parser.parse_args()
    data2 = dataset_root(args.data) / "Bandai-Namco-Research-Motiondataset-2" / "data"
    paths = [p for content in NEUTRAL_CONTENTS for p in sorted(data2.glob(f"dataset-2_{content}_normal_*.bvh"))]
    model = BodyModel.load()
    motions = em.read_bvh_many(paths)
    P = np.concatenate([pose_vectors(m.rotations, model.predicted, model.hemispheres) for m in motions])
    groups = np.concatenate([np.full(m.n_frames, k) for k, m in enumerate(motions)])
    results = sweep_autoencoder(P, groups, max_iter=args.max_iter)
    out = HERE / "sweep_autoencoder.json"
    out.write_text(json.dumps({str(h): r.to_json() for h, r in results.items()}, indent=1))
    print("| hidden units | train MSE | test MSE | test variance explained |\n|---|---|---|---|")
    for hidden, r in results.items():
        print(f"| {hidden} | {r.train_mse:.3g} | {r.test_mse:.3g} | {r.test_variance_explained:.4f} |")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
