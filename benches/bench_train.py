"""Training time of the body-mechanics network on synthetic data of the real size: ~50k frames
in clips of 75, 19 features, D = 80 pose values, H = 300, every stage (and the plain network).

    PYTHONPATH=python python benches/bench_train.py [--clips 667] [--frames 75] [--max-iter 400]

Poses are ``tanh(X A) B`` plus noise on a 6-D manifold (as in tests/decoupling/test_training.py), so the MSE
figures say the optimiser works, not how well real poses are predicted. Checked before the total
is printed (benches/harness.py; a failed check raises): every row in the train/test split, and the
network's test MSE finite and below the mean pose's.
"""

from __future__ import annotations

import argparse
import math
import os

from expressive_mocap.decoupling.training import synthetic_data, train_stacked_network
from harness import check, check_equal, timed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=667)
    parser.add_argument("--frames", type=int, default=75)
    parser.add_argument("--hidden", type=int, default=300)
    parser.add_argument("--max-iter", type=int, default=400)
    args = parser.parse_args()
    X, P, groups = synthetic_data(args.clips, args.frames)
    print(
        f"{len(X)} rows, {X.shape[1]} features, D = {P.shape[1]}, H = "
        f"{args.hidden}, max_iter {args.max_iter} a stage, {os.cpu_count()} cpus"
    )
    seconds, (_, report) = timed(
        train_stacked_network,
        X,
        P,
        groups,
        hidden=args.hidden,
        regression_hidden=args.hidden,
        max_iter=args.max_iter,
        log=lambda line: print(line, flush=True),
    )
    split, fine_tuned, mean_pose = report.split, report.fine_tuned, report.mean_pose
    assert split is not None and fine_tuned is not None and mean_pose is not None
    check_equal((split.train_rows or 0) + (split.test_rows or 0), len(X), "rows in the train/test split")
    network, baseline = fine_tuned.test_mse, mean_pose.test_mse
    check(
        network is not None and baseline is not None and math.isfinite(network) and network < baseline,
        f"test MSE {network:.4g}: not below the mean pose's",
    )
    print(f"total {seconds:.0f} s")  # the report above comes from the training log


if __name__ == "__main__":
    main()
