"""Per-frame latency of the streaming decoupler: python benches/bench_streaming.py

Feeds the procedural walk-plus-wave (embedded, no data needed) one frame at a time to
StreamingDecoupler with the shipped model, Rust kernels and NumPy twins in the same run.
"""

from __future__ import annotations

import time

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.streaming import StreamingDecoupler
from expressive_mocap.demo import walk_and_wave


def latencies(motion: em.Motion, model: BodyModel) -> np.ndarray:
    stream = StreamingDecoupler(model, motion.skeleton, motion.frame_time)
    out = []
    for f in range(motion.n_frames):
        start = time.perf_counter()
        stream.push(motion.rotations[f], motion.translations[f])
        out.append(time.perf_counter() - start)
    return np.array(out[60:])  # after the 2 s history has filled


def main() -> None:
    motion = walk_and_wave(seconds=10.0).waving
    model = BodyModel.load()
    print(
        f"streaming decoupler, {motion.n_frames} frames at {motion.fps:g} "
        f"fps (budget {1000 * motion.frame_time:.1f} ms a frame)"
    )
    print("| kernels | median ms | 95th percentile ms | max ms |\n|---|---|---|---|")
    for backend in ("rust", "numpy"):
        with em.use_backend(backend):
            t = latencies(motion, model) * 1000
        print(f"| {backend} | {np.median(t):.2f} | {np.percentile(t, 95):.2f} | {t.max():.2f} |")


if __name__ == "__main__":
    main()
