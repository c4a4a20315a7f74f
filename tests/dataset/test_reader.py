"""A Dataset (``load_dataset``) follows sequence and mapping conventions: clips by index, by name
and in order; a kind name as a key still gives the whole array, with a warning."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.procedural import procedural_walk


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    folder = tmp_path_factory.mktemp("api") / "clips"
    folder.mkdir()
    for k, seconds in enumerate((0.6, 0.4, 0.5)):
        em.write_bvh(procedural_walk(seconds=seconds), folder / f"walk_{k}.bvh")
    out = folder.parent / "ds"
    preprocess(folder, out, keep="positions,contacts", progress=False)
    return load_dataset(out)


def test_a_dataset_is_a_sequence_of_clips(dataset):
    ds = dataset
    # Failed before: ds[0] raised KeyError (ds[...] took kinds only) and iteration failed with it.
    first, last = ds[0], ds[-1]
    assert len(ds) == 3 and ds.kinds == ("positions", "contacts")
    assert (first.name, last.name) == ("walk_0", "walk_2") and first.index == 0 and last.index == 2
    assert [clip.name for clip in ds] == ds.names
    assert ds["walk_1"].index == 1 and "walk_1" in ds and "walk_9" not in ds
    for i, clip in enumerate(ds):
        rows = slice(ds.offsets[i], ds.offsets[i + 1])
        assert clip.frames == ds.clips[i]["frames"] == rows.stop - rows.start
        assert dict(clip).keys() == {"positions", "contacts"}
        np.testing.assert_array_equal(clip["positions"], ds.positions[rows])
        assert clip.contacts is clip["contacts"] and np.shares_memory(clip.positions, ds.arrays["positions"])
    with pytest.raises(IndexError, match="clip 3 of a dataset of 3 clips"):
        ds[3]
    with pytest.raises(KeyError, match="no clip named 'walk_9'"):
        ds["walk_9"]
    with pytest.raises(AttributeError, match="kinds are positions, contacts"):
        ds.features  # noqa: B018
    with pytest.raises(KeyError, match="kinds are positions, contacts"):
        first["features"]


def test_a_kind_name_as_a_key_still_gives_the_whole_array_with_a_warning(dataset):
    with pytest.warns(DeprecationWarning, match=r"ds\.positions"):
        whole = dataset["positions"]
    assert whole is dataset.positions is dataset.arrays["positions"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        dataset["walk_0"]  # a clip name: no warning
