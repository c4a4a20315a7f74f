"""Frames per second delivered by the training loader: python benches/bench_loader.py DATASET

Shuffled 64-frame windows (stride 16), batches of 256, from a memory-mapped dataset (e.g. the
whole dataset-2 archive preprocessed with ``--keep positions,rotations,contacts``), through
:class:`~expressive_mocap.dataset.Batches` in this process: plain, normalised, and with each
augmentation. Frames delivered = windows x 64. The page cache is warmed by a first pass, so the
figures are of the loader, not of the disk. Each repeat's first batch is checked once its time is
taken (benches/harness.py; a failed check raises): some windows, every kind asked for, 64 frames a
window, finite values.
"""

from __future__ import annotations

import argparse

import numpy as np

from expressive_mocap.dataset import Augment, load_dataset, window_batches
from harness import check, check_equal, clock

LENGTH, STRIDE, BATCH = 64, 16, 256  # frames a window, frames between windows, windows a batch

CASES = {
    "plain": {},
    "normalised": {"normalise": True},
    "rotation": {"augment": Augment(rotate=True)},
    "speed 0.8-1.25": {"augment": Augment(speed=(0.8, 1.25))},
    "noise 0.01": {"augment": Augment(noise=0.01)},
    "rotation + speed, normalised": {"augment": Augment(rotate=True, speed=(0.8, 1.25)), "normalise": True},
    "all three, normalised": {"augment": Augment(rotate=True, speed=(0.8, 1.25), noise=0.01), "normalise": True},
}


def check_batch(batch, kinds: list[str], what: str) -> None:
    """One delivered batch (NumPy arrays or tensors): some windows, each kind ``[B, LENGTH, ...]``, finite."""
    check(batch is not None, f"{what}: no batch delivered")
    windows = int(batch["clip"].shape[0])
    check(0 < windows <= BATCH, f"{what}: {windows} windows in a batch")
    for kind in kinds:
        check_equal(tuple(batch[kind].shape[:2]), (windows, LENGTH), f"{what}: shape of {kind}")
        check(np.isfinite(np.asarray(batch[kind])).all(), f"{what}: {kind} not finite")


def rate(passes, batches: int, kinds: list[str], what: str) -> float:
    """Frames per second over the first ``batches`` batches of ``passes(n)``, the n-th pass over
    the data (best of 3 passes); each pass's first batch checked after its time is taken."""
    best = 0.0
    for repeat in range(3):
        frames, first, start = 0, None, clock()
        for i, batch in enumerate(passes(repeat)):
            first = batch if first is None else first
            frames += batch["clip"].shape[0] * LENGTH
            if i + 1 == batches:
                break
        best = max(best, frames / (clock() - start))
        check_batch(first, kinds, what)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("dataset")
    parser.add_argument("--batches", type=int, default=100, help="batches timed per repeat (default 100)")
    parser.add_argument("--torch", action="store_true", help="also through a PyTorch DataLoader")
    parser.add_argument("--kinds", help="comma-separated kinds to load (default: positions,rotations,contacts)")
    args = parser.parse_args()
    ds = load_dataset(args.dataset)
    print(ds)
    wanted = args.kinds.split(",") if args.kinds else ("positions", "rotations", "contacts")
    kinds = [k for k in wanted if k in ds.kinds]
    warm = window_batches(ds, LENGTH, STRIDE, batch_size=BATCH, kinds=kinds, shuffle=False)
    for _ in warm.epoch(0):  # the page cache
        pass
    windows = len(warm.reader.windows)
    print(f"{windows:,} windows of {LENGTH} frames, stride {STRIDE}; batches of {BATCH}; kinds {', '.join(kinds)}")
    print("| case | frames/s | batches/s |\n|---|---|---|")
    for name, options in CASES.items():
        loader = window_batches(ds, LENGTH, STRIDE, batch_size=BATCH, kinds=kinds, seed=0, **options)
        frames = rate(loader.epoch, args.batches, kinds, name)
        print(f"| {name} | {frames / 1e6:.2f} M | {frames / (BATCH * LENGTH):.0f} |")
    if args.torch:
        torch_rates(args.dataset, kinds, args.batches)


def torch_rates(folder: str, kinds: list[str], batches: int) -> None:
    """The same windows through WindowDataset and a PyTorch DataLoader (tensors out)."""
    import torch

    from expressive_mocap.dataset import WindowDataset

    print(f"\nPyTorch DataLoader over WindowDataset (batch {BATCH}, shuffled; tensors delivered)")
    print("| case | workers | frames/s |\n|---|---|---|")
    for name, augment in (("plain", None), ("rotation + speed", Augment(rotate=True, speed=(0.8, 1.25)))):
        dataset = WindowDataset(folder, LENGTH, STRIDE, kinds=kinds, augment=augment)
        for workers in (0, 2):
            loader = torch.utils.data.DataLoader(
                dataset, batch_size=256, shuffle=True, num_workers=workers, persistent_workers=workers > 0
            )
            best = rate(lambda _, loader=loader: loader, batches, kinds, f"torch, {name}")
            print(f"| {name} | {workers} | {best / 1e6:.2f} M |")
        sampler = torch.utils.data.BatchSampler(torch.utils.data.RandomSampler(dataset), BATCH, drop_last=False)
        for workers in (0, 2):
            loader = torch.utils.data.DataLoader(
                dataset, batch_size=None, sampler=sampler, num_workers=workers, persistent_workers=workers > 0
            )
            best = rate(lambda _, loader=loader: loader, batches, kinds, f"torch, {name}, BatchSampler")
            print(f"| {name}, whole batches (BatchSampler) | {workers} | {best / 1e6:.2f} M |")


if __name__ == "__main__":
    main()
