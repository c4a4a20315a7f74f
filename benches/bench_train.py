"""Training time of the body-mechanics network on synthetic data of the real size: ~50k frames
in clips of 75, 19 features, D = 80 pose values, H = 300, every stage (and the plain network).

    PYTHONPATH=python python benches/bench_train.py [--clips 667] [--frames 75] [--max-iter 400]

Poses are ``tanh(X A) B`` plus noise on a 6-D manifold (as in tests/test_train.py), so the MSE
figures say the optimiser works, not how well real poses are predicted.
"""

from __future__ import annotations

import argparse
import os
import time

from expressive_mocap.decoupling.training import synthetic_data, train_stacked_network


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
    start = time.perf_counter()
    train_stacked_network(
        X,
        P,
        groups,
        hidden=args.hidden,
        regression_hidden=args.hidden,
        max_iter=args.max_iter,
        log=lambda line: print(line, flush=True),
    )
    print(f"total {time.perf_counter() - start:.0f} s")  # the report above comes from the training log


if __name__ == "__main__":
    main()
