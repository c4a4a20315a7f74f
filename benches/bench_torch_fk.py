"""Forward kinematics in PyTorch on the CPU against the package's Rust kernel and its NumPy twin:

    PYTHONPATH=python python benches/bench_torch_fk.py [DATA] [--repeat 15]

A batch of 256 windows of 64 frames (16,384 frames) of the 22-joint Bandai-Namco skeleton: the
local rotations of dataset-2 clips (DATA: its folder of BVH files; by default the unpacked copy
the tests use, else random rotations on that skeleton). The kernel and its twin take float64
``[16384, 22, 4]`` and per-frame translations (their interface); torch takes the float32 batch
``[256, 64, 22, 4]`` twice: with the rest offsets ``[22, 3]`` and the hips' positions (how a
training loss calls it), and with the kernel's per-frame translations. Forward+backward of the
first is timed too. Calls alternate (benches/harness.py ``rotated``), the best of ``--repeat`` is
kept; the results are checked against the kernel's first (a failed check raises). Real clips:
Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np
import torch

import expressive_mocap as em
from expressive_mocap import reference
from expressive_mocap.backend import kernels
from expressive_mocap.dataset.torch_ops import forward_kinematics
from harness import Best, check, check_close, cpu_name, rotated

WINDOWS, FRAMES = 256, 64
DEFAULT_DATA = (
    Path(os.environ.get("EXPRESSIVE_MOCAP_DATA_CACHE", Path.home() / ".cache" / "motion-data"))
    / "dataset"
    / "Bandai-Namco-Research-Motiondataset-2"
    / "data"
)
BANDAI_PARENTS = [-1, 0, 1, 2, 3, 4, 3, 6, 7, 8, 3, 10, 11, 12, 1, 14, 15, 16, 1, 18, 19, 20]


def real_batch(folder: Path, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Rotations ``[W, T, 22, 4]``, translations ``[W, T, 22, 3]`` and the parents, of windows
    drawn from the clips of ``folder``."""
    paths = sorted(folder.glob("dataset-2_*.bvh"))
    rotations, translations = [], []
    picked = rng.choice(len(paths), size=min(64, len(paths)), replace=False)
    motions = [em.read_bvh(paths[i]) for i in picked]
    motions = [m for m in motions if m.n_frames >= FRAMES]
    for w in range(WINDOWS):
        m = motions[w % len(motions)]
        start = int(rng.integers(0, m.n_frames - FRAMES + 1))
        rotations.append(m.rotations[start : start + FRAMES])
        translations.append(m.translations[start : start + FRAMES])
    parents = np.asarray(motions[0].skeleton.parents)
    return np.stack(rotations), np.stack(translations), parents, f"real rotations of {len(motions)} dataset-2 clips"


def random_batch(rng) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    q = rng.normal(size=(WINDOWS, FRAMES, 22, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    offsets = rng.normal(size=(22, 3)) * 20
    translations = np.broadcast_to(offsets, q.shape[:-1] + (3,)).copy()
    translations[..., 1, :] += rng.normal(size=(WINDOWS, FRAMES, 3)) * 100  # moving hips
    return q, translations, np.array(BANDAI_PARENTS), "random rotations (no data found)"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT_DATA)
    parser.add_argument("--repeat", type=int, default=15)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    has_data = args.data.is_dir() and any(args.data.glob("dataset-2_*.bvh"))
    q, t, parents, what = real_batch(args.data, rng) if has_data else random_batch(rng)
    rows = WINDOWS * FRAMES
    q64, t64 = np.ascontiguousarray(q.reshape(rows, 22, 4)), np.ascontiguousarray(t.reshape(rows, 22, 3))
    rust = kernels() if em.rust_available() else None
    check(rust is not None and rust is not reference, "the Rust extension is not built")
    world, positions = rust.forward_kinematics(q64, t64, parents)

    # torch: float32, as a training step holds it
    rq = torch.tensor(q, dtype=torch.float32)
    offsets = torch.tensor(t[0, 0], dtype=torch.float32)  # the rest offsets: every frame's but the hips'
    hips = torch.tensor(positions.reshape(WINDOWS, FRAMES, 22, 3)[:, :, 1], dtype=torch.float32)
    per_frame = torch.tensor(t, dtype=torch.float32)
    scale = float(np.abs(positions).max())

    def torch_offsets():
        return forward_kinematics(rq, offsets, parents, hips, root=1)

    def torch_translations():
        return forward_kinematics(rq, per_frame, parents)

    grad_q = rq.clone().requires_grad_()

    def torch_backward():
        _, p = forward_kinematics(grad_q, offsets, parents, hips, root=1)
        p.square().sum().backward()
        return p

    for label, fn in (("offsets", torch_offsets), ("translations", torch_translations)):
        got_q, got_p = fn()
        check_close(got_q.reshape(rows, 22, 4), world, f"torch ({label}) world rotations", atol=1e-5)
        check_close(got_p.reshape(rows, 22, 3) / scale, positions / scale, f"torch ({label}) positions", atol=1e-5)
    check_close(reference.forward_kinematics(q64, t64, parents)[1] / scale, positions / scale, "NumPy twin", atol=1e-12)

    cases = {
        "rust": lambda: rust.forward_kinematics(q64, t64, parents),
        "numpy": lambda: reference.forward_kinematics(q64, t64, parents),
        "torch": torch_offsets,
        "torch (per-frame translations)": torch_translations,
        "torch forward+backward": torch_backward,
    }
    best = Best()
    for r in range(args.repeat):
        for label in rotated(list(cases), r):
            best.time(label, cases[label])

    print(f"{cpu_name()}, {os.cpu_count()} cpus; torch {torch.__version__} ({torch.get_num_threads()} threads), "
          f"NumPy {np.__version__}; rayon threads {em._core.num_threads}")  # fmt: skip
    print(f"FK of {WINDOWS} windows x {FRAMES} frames x 22 joints ({what}), best of {args.repeat}:")
    for label, seconds in best.items():
        print(f"  {label:32s} {seconds * 1e3:8.2f} ms   {seconds / best['rust']:6.2f}x rust")
    print(f"  torch / rust {best['torch'] / best['rust']:.2f}x, numpy / torch {best['numpy'] / best['torch']:.1f}x")
    print("reproduce: PYTHONPATH=python python benches/" + Path(sys.argv[0]).name)


if __name__ == "__main__":
    main()
