"""WindowDataset under a real PyTorch DataLoader (two worker processes) and a short training
loop, on six real dataset-2 clips (Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0). Skipped
when torch is not installed (``pip install '.[torch]'``)."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

from expressive_mocap.dataset import Augment, Labels, WindowDataset, Windows, load_dataset, split
from training_clips import training_dataset

torch = pytest.importorskip("torch")
pytestmark = pytest.mark.torch


@pytest.fixture(scope="module")
def folder(bandai2_dir, tmp_path_factory):
    return training_dataset(bandai2_dir, tmp_path_factory.mktemp("torch"))


def test_it_pickles_as_its_folder_and_settings(folder):
    windows = WindowDataset(folder, 32, 16, labels="bandai", normalise=True)
    assert len(windows) > 0 and windows._reader is not None
    data = pickle.dumps(windows)
    assert b"positions.npy" not in data and len(data) < 4096  # no arrays, no memory maps
    copy = pickle.loads(data)
    assert copy._reader is None  # reopened on first use
    for i in (0, len(windows) - 1):
        a, b = windows[i], copy[i]
        for key in ("positions", "rotations", "contacts", "clip", "start"):
            np.testing.assert_array_equal(a[key], b[key])
        assert a["labels"] == b["labels"]


def test_a_dataloader_with_two_workers_delivers_every_window_once(folder):
    ds = load_dataset(folder)
    parts = split(ds, by="clip", fractions={"train": 0.5, "test": 0.5}, seed=2)
    clips = parts["train"] if len(parts["train"]) else parts["test"]
    dataset = WindowDataset(folder, 48, 24, padding="edge", clips=clips, labels="bandai")
    loader = torch.utils.data.DataLoader(dataset, batch_size=8, shuffle=True, num_workers=2)
    windows = Windows(ds, 48, 24, "edge", clips)
    labels = Labels.from_names(ds)
    seen = []
    for batch in loader:
        assert isinstance(batch["positions"], torch.Tensor) and batch["positions"].dtype == torch.float32
        assert batch["positions"].shape[1:] == (48, 22, 3) and batch["contacts"].shape[1:] == (48, 2)
        for j in range(len(batch["clip"])):
            clip, start = int(batch["clip"][j]), int(batch["start"][j])
            (w,) = np.flatnonzero((windows.clip == clip) & (windows.offset == start))
            np.testing.assert_array_equal(batch["positions"][j].numpy(), windows.read(ds.positions, w))
            assert int(batch["labels"]["style"][j]) == labels.codes["style"][clip]
            seen.append(w)
    assert sorted(seen) == list(range(len(windows)))


def test_a_short_training_loop_learns_from_augmented_batches(folder):
    """A small network predicting the foot contacts from the heights of normalised, rotated,
    sped-up positions (heights do not change under rotation about the vertical) lowers its loss
    well below chance: the batches carry what they say, windows and contacts aligned."""
    torch.manual_seed(0)
    dataset = WindowDataset(
        folder,
        16,
        8,
        kinds=["positions", "contacts"],
        augment=Augment(rotate=True, speed=(0.9, 1.1), noise=0.01),
        normalise=True,
        seed=1,
    )
    loader = torch.utils.data.DataLoader(dataset, batch_size=32, shuffle=True, num_workers=2)
    model = torch.nn.Sequential(torch.nn.Linear(22, 32), torch.nn.ReLU(), torch.nn.Linear(32, 2))
    optimiser = torch.optim.Adam(model.parameters(), lr=1e-2)
    losses = []
    for epoch in range(12):
        dataset.set_epoch(epoch)
        total, count = 0.0, 0
        for batch in loader:
            positions = batch["positions"]
            logits = model(positions[..., 1])  # Y up: the joints' (normalised) heights
            loss = torch.nn.functional.binary_cross_entropy_with_logits(logits, batch["contacts"])
            optimiser.zero_grad()
            loss.backward()
            optimiser.step()
            total, count = total + float(loss.detach()) * len(positions), count + len(positions)
        losses.append(total / count)
    assert losses[-1] < 0.6 * losses[0]


def test_getitems_returns_the_same_windows_as_getitem(folder):
    dataset = WindowDataset(folder, 40, 13, padding="zero")
    picked = [5, 0, len(dataset) - 1, 5, 17]
    many = dataset.__getitems__(picked)
    for i, item in zip(picked, many):
        single = dataset[i]
        for key in ("positions", "rotations", "contacts", "clip", "start", "valid"):
            np.testing.assert_array_equal(item[key], single[key])


def test_whole_batches_through_a_batch_sampler(folder):
    ds = load_dataset(folder)
    dataset = WindowDataset(folder, 24, 24, padding="zero", kinds=["positions", "contacts"])
    windows = Windows(ds, 24, 24, "zero")
    sampler = torch.utils.data.BatchSampler(torch.utils.data.RandomSampler(dataset), 16, drop_last=False)
    loader = torch.utils.data.DataLoader(dataset, batch_size=None, sampler=sampler, num_workers=2)
    seen = []
    for batch in loader:
        assert set(batch) >= {"positions", "contacts", "window", "clip", "start", "valid"}
        for j, w in enumerate(batch["window"].tolist()):
            np.testing.assert_array_equal(batch["positions"][j].numpy(), windows.read(ds.positions, w))
            np.testing.assert_array_equal(batch["contacts"][j].numpy(), windows.read(ds.contacts, w))
            seen.append(w)
    assert sorted(seen) == list(range(len(windows)))
