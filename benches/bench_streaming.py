"""Per-frame latency of the streaming decoupler: python benches/bench_streaming.py

Feeds the procedural walk-plus-wave (embedded, no data needed) one frame at a time to
StreamingDecoupler with the shipped model, Rust kernels and NumPy twins in the same run. Checked
before the table (benches/harness.py; a failed check raises): every frame answered, and the Rust
kernels' body mechanics, expressive component and activity within 1e-12 of the twins'.
"""

from __future__ import annotations

import numpy as np

import expressive_mocap as em
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.streaming import StreamingDecoupler
from expressive_mocap.procedural import walk_and_wave
from harness import check_close, check_equal, timed

TOLERANCE = 1e-12  # Rust against the twins: 2.5e-14 measured


def latencies(motion: em.Motion, model: BodyModel) -> tuple[np.ndarray, list]:
    """Seconds of each push after the 2 s history has filled, and every push's output."""
    stream = StreamingDecoupler(model, motion.skeleton, motion.frame_time)
    out, outputs = [], []
    for f in range(motion.n_frames):
        seconds, answer = timed(stream.push, motion.rotations[f], motion.translations[f])
        out.append(seconds)
        outputs.append(answer)
    return np.array(out[60:]), outputs  # after the 2 s history has filled


def main() -> None:
    motion = walk_and_wave(seconds=10.0).waving
    model = BodyModel.load()
    print(
        f"streaming decoupler, {motion.n_frames} frames at {motion.fps:g} "
        f"fps (budget {1000 * motion.frame_time:.1f} ms a frame)"
    )
    times, outputs = {}, {}
    for backend in ("rust", "numpy"):
        with em.use_backend(backend):
            seconds, outputs[backend] = latencies(motion, model)
        times[backend] = seconds * 1000
    check_equal(len(outputs["rust"]), motion.n_frames, "frames answered")
    for part, name in enumerate(("body mechanics", "expressive component", "activity")):
        check_close(
            np.stack([o[part] for o in outputs["rust"]]),
            np.stack([o[part] for o in outputs["numpy"]]),
            f"{name}, Rust against the twins",
            atol=TOLERANCE,
        )
    print("| kernels | median ms | 95th percentile ms | max ms |\n|---|---|---|---|")
    for backend, t in times.items():
        print(f"| {backend} | {np.median(t):.2f} | {np.percentile(t, 95):.2f} | {t.max():.2f} |")


if __name__ == "__main__":
    main()
