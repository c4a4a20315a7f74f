"""Preprocessing a whole archive of BVH clips into a dataset of arrays (``expressive-mocap preprocess``),
and reading it back (:func:`load_dataset`).

Per clip: parse, forward kinematics (world positions), dynamic features, foot contacts and,
with a body-mechanics model, the decomposition's activity per joint (optionally its body and
expressive rotations). Clips are read in batches. Python reads each clip's header from the
file's first bytes (:func:`~expressive_mocap.bvh.read_header`); everything else of a clip
(reading the file, its MOTION block, FK, features, contacts, float32 outputs) is one task of
one Rust call per batch, clips in parallel (``clip_pipeline_many``), then the network runs on
the whole batch. Header threads prepare the next batches while a kernel thread runs this one's
kernels and the main thread appends the previous one's rows to the output, so memory stays
bounded and both cores stay busy (the kernels release the GIL).

The output format: a folder ::

    OUT/manifest.json      clips (name, source, frames, fps, start row), failures with their
                           errors, the skeleton (joint names, parents), the kinds kept and their
                           shapes, the options, the positions' up axis, each float kind's mean
                           and std ("stats"), the package version; written last
    OUT/offsets.npy        int64 [C + 1]: clip i is rows offsets[i]:offsets[i + 1] of every kind
    OUT/positions.npy      float32 [N, J, 3]  positions (file units; world, or --positions' frame)
    OUT/rotations.npy      float32 [N, J, n]  local rotations (x, y, z, w; or --rotations' form)
    OUT/features.npy       float32 [N, 19]    dynamic_features (causal; FEATURE_NAMES)
    OUT/contacts.npy       bool    [N, 2]     foot_contacts (offline; left, right)
    OUT/activity.npy       float32 [N, J]     decomposition activity per joint (--model)
    OUT/body.npy, OUT/expressive.npy  float32 [N, J, 4]  B' and E* (--model)
    OUT/velocities.npy, accelerations.npy, root_velocity.npy [N, 4], angular_velocities.npy
                           time derivatives (:mod:`.derive`; docs/preprocessing.md)

(N = frames of all clips, rows in clip order.) Why NumPy ``.npy`` files and a JSON manifest:
they need nothing beyond NumPy, every array can be memory-mapped (``np.load(mmap_mode="r")``:
a 500 MB archive opens in milliseconds and a training loop reads only the rows it touches),
one concatenated array per kind is what batch samplers want (clip ``i`` is one slice), and
the whole dataset loads in one line: ``load_dataset(OUT)``. HDF5 or Zarr would add a
dependency for little gain here; ``.npz`` cannot be memory-mapped; Parquet does not hold
``[N, J, 3]`` tensors naturally.

Robustness: a clip that cannot be read or processed is listed in the manifest's failures with
its error and the run goes on. The run writes into ``OUT/.partial``: each batch's rows are
appended to the data files, then one line is appended to a journal; an interrupted run
restarts from the journal (the data files are cut back to the last journaled batch, finished
clips are skipped). At the end the data are synced to disk, the files renamed into ``OUT`` and
the manifest written last: a folder with a ``manifest.json`` is a complete dataset, never a
half-written one. (An interrupted process loses nothing; the journal is not synced per batch,
so after a power cut mid-run delete ``OUT/.partial`` and run again.)

Safety (:mod:`.lock`, :mod:`.folder`, :mod:`.format`): a run holds an advisory lock on ``OUT/.lock`` from start
to end, so a second run on the same OUT fails at once naming the first; OUT must be new, empty,
or one of our datasets (finished or unfinished), never a folder of the user's own files; a rerun
over a finished dataset never rewrites it (``overwrite`` redoes it, deleting only the format's
own file names); clips are keyed by name, so a resumed run may spell SRC otherwise, and a
second clip of a name already taken is a failure; the manifest records each file's size and
mtime, and :func:`load_dataset` refuses files that do not match it.

The modules: :mod:`.sources` (the clips of SRC), :mod:`.work` (one batch's headers and
kernels; the model through :func:`expressive_mocap.decoupling.decompose_many`), :mod:`.derive`
(the model-ready forms: rotation forms, position frames, time derivatives, resampling),
:mod:`.forms` (a batch's forms after its kernels: mirror images, heading frame, sums),
:mod:`.stats` (normalisation statistics), :mod:`.pipeline` (threads on
this machine), :mod:`.cluster` (Dask), :mod:`.collect` (a batch's outcomes into its journal
record), :mod:`.npy` (the data files written in pieces), :mod:`.journal`, :mod:`.finish` (the
manifest, last), :mod:`.run` (:func:`preprocess`), :mod:`.summary`; :mod:`.format` (file names,
manifest checks, verification), :mod:`.lock`, :mod:`.folder` (whose folder it is),
:mod:`.reader` (:class:`Dataset`, :func:`load_dataset`).

For training (docs/training.md): :mod:`.stats` (:class:`Normaliser`), :mod:`.labels`
(:class:`Labels` from names or a CSV), :mod:`.splits` (:func:`split`), :mod:`.windows`
(:class:`Windows`, views), :mod:`.transforms` (per-sample augmentation: :class:`Compose` of
:class:`RandomRotation`, :class:`Mirror`, :class:`Speed`, :class:`Noise`, :class:`JointDropout`),
:mod:`.augment` (what they do to each kind; :class:`Augment`, a shorthand), :mod:`.batches`
(:class:`WindowReader`, :class:`Batches`, :func:`window_batches`) and :mod:`.torch_dataset`
(:class:`WindowDataset` for a PyTorch ``DataLoader``).
"""

from .._utils.lazy import lazy_exports
from .format import KINDS
from .lock import FolderLock
from .reader import Clip, Dataset, load_dataset

# The writing side and the training helpers load on first use: load_dataset stays light.
_LAZY = {
    "Summary": "summary",
    "open_source": "sources",
    "preprocess": "run",
    "Normaliser": "stats",
    "compute_stats": "stats",
    "Labels": "labels",
    "BANDAI": "labels",
    "split": "splits",
    "Windows": "windows",
    "clip_windows": "windows",
    "Augment": "augment",
    "Compose": "transforms",
    "RandomRotation": "transforms",
    "Mirror": "transforms",
    "Speed": "transforms",
    "Noise": "transforms",
    "JointDropout": "transforms",
    "WindowReader": "batches",
    "Batches": "batches",
    "window_batches": "batches",
    "WindowDataset": "torch_dataset",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())


__all__ = [
    "BANDAI",
    "KINDS",
    "Augment",
    "Batches",
    "Clip",
    "Compose",
    "Dataset",
    "FolderLock",
    "JointDropout",
    "Labels",
    "Mirror",
    "Noise",
    "Normaliser",
    "RandomRotation",
    "Speed",
    "Summary",
    "WindowDataset",
    "WindowReader",
    "Windows",
    "window_batches",
    "clip_windows",
    "compute_stats",
    "load_dataset",
    "open_source",
    "preprocess",
    "split",
]
