"""MLP inference speed: the Rust kernel vs its NumPy twin, on a 19 -> 300 -> 300 -> 80 stack
(the body-mechanics network's shape) over 100k rows, float32 and float64.

    PYTHONPATH=python python benches/bench_mlp.py [--rows 100000] [--repeat 5]

Calls alternate between the two backends and the best of ``--repeat`` is kept (machines here
drift by 30-40%: only ratios taken in the same run are comparable). Checked first
(benches/harness.py; a failed check raises): the Rust output within 1e-4 (float32) or 1e-12
(float64) of the twin's, outputs being of order 1.
"""

from __future__ import annotations

import argparse
import os
import platform

import numpy as np

from expressive_mocap import _core, reference
from harness import Best, check_close

TOLERANCE = {np.float32: 1e-4, np.float64: 1e-12}  # measured: 2.1e-6 and 3.3e-15


def net_arrays(rng, widths, dtype):
    weights = [(rng.normal(size=(a, b)) / np.sqrt(a)).astype(dtype) for a, b in zip(widths[:-1], widths[1:])]
    biases = [rng.normal(scale=0.1, size=b).astype(dtype) for b in widths[1:]]
    activations = ["tanh"] * (len(widths) - 2) + ["linear"]
    return weights, biases, activations


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=100_000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    widths = (19, 300, 300, 80)
    flops = 2 * args.rows * sum(a * b for a, b in zip(widths[:-1], widths[1:]))
    print(
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} "
        f"cpus, rayon threads {_core.num_threads}, NumPy {np.__version__}"
    )
    print(
        f"network {' -> '.join(map(str, widths))}, {args.rows} rows, "
        f"{flops / 1e9:.1f} GFLOP a pass, best of {args.repeat}"
    )
    for dtype in (np.float32, np.float64):
        rng = np.random.default_rng(0)
        weights, biases, activations = net_arrays(rng, widths, dtype)
        x = rng.normal(size=(args.rows, widths[0])).astype(dtype)
        check_close(
            _core.mlp_forward(x, weights, biases, activations),
            reference.mlp_forward(x, weights, biases, activations),
            f"{np.dtype(dtype).name} output, Rust against the twin",
            atol=TOLERANCE[dtype],
        )
        best = Best()
        for _ in range(args.repeat):
            for name, module in (("rust", _core), ("numpy", reference)):
                out = best.time(name, module.mlp_forward, x, weights, biases, activations)
            del out
        rust, numpy = best["rust"], best["numpy"]
        print(
            f"{np.dtype(dtype).name:8s} rust {rust * 1e3:7.1f} ms ({args.rows / rust / 1e6:5.2f} "
            f"M rows/s, {flops / rust / 1e9:5.1f} GFLOP/s)   numpy {numpy * 1e3:7.1f} ms "
            f"({args.rows / numpy / 1e6:5.2f} M rows/s)   numpy/rust {numpy / rust:4.2f}x"
        )


if __name__ == "__main__":
    main()
