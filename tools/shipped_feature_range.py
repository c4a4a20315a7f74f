"""Give the shipped model its feature range: python tools/shipped_feature_range.py [--data DIR]

`train` stores the range of features a body model trusts its network with (the lowest and
highest of its training clips' features; inputs are clipped into it). The shipped model was trained
before that, so this script computes the range as `train` would, from the same neutral clips in
the same order and the same 70/30 split by clip (seed 0), and writes it into
python/expressive_mocap/data/body_model.npz; the network is unchanged.

Data: Bandai-Namco-Research-Motiondataset 2 (Bandai Namco Research Inc., 2022; Kobayashi et
al., arXiv:2306.08861), CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling.body_model import BodyModel, model_features
from expressive_mocap.decoupling.training import FEATURE_RANGE, feature_range, split_by_group

HERE = Path(__file__).resolve().parent
SHIPPED = HERE.parent / "python" / "expressive_mocap" / "data" / "body_model.npz"
NEUTRAL_CONTENTS = ("walk", "walk-turn-left", "walk-turn-right", "run")  # the training command's order


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--data", help="folder holding Bandai-Namco-Research-Motiondataset-2")
    args = parser.parse_args()
    root = Path(args.data) if args.data else Path.home() / ".cache" / "motion-data" / "dataset"
    data2 = root / "Bandai-Namco-Research-Motiondataset-2" / "data"
    paths = [p for c in NEUTRAL_CONTENTS for p in sorted(data2.glob(f"dataset-2_{c}_normal_*.bvh"))]
    model = BodyModel.load(SHIPPED)
    motions = em.read_bvh_many(paths)
    if sum(m.n_frames for m in motions) != model.settings.neutral_frames:
        raise SystemExit("these clips are not the ones the shipped model was trained on")
    features = np.concatenate([model_features(m, model.thigh_reference) for m in motions])
    groups = np.concatenate([np.full(m.n_frames, k) for k, m in enumerate(motions)])
    train_rows, _ = split_by_group(groups, 0.3, model.settings.seed or 0)
    settings = replace(model.settings, feature_range=FEATURE_RANGE)
    replace(model, feature_range=feature_range(features[train_rows]), settings=settings).save(SHIPPED)
    print(f"wrote the feature range of {len(train_rows)} training frames into {SHIPPED}")


if __name__ == "__main__":
    main()
