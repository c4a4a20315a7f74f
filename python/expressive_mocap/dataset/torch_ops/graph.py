"""The skeleton of a dataset as a graph, for graph networks and for forward kinematics: its joints'
parents, bone lengths and rest offsets, the joint that carries the root motion, the feet, and the
adjacency matrix and edge list of the bones. NumPy arrays, with tensors on request."""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
import torch

from ...errors import ArgumentError, MocapError
from ...motion import Skeleton
from ..reader import Dataset, load_dataset

# Frames, evenly spread over the dataset, that bone lengths and offsets are read from.
SAMPLED_FRAMES = 2048


@dataclass(frozen=True, eq=False)
class SkeletonGraph:
    """A skeleton's joints as a graph (``J`` joints, ``J - roots`` bones).

    ``names``, ``parents [J]`` (int64, roots -1); ``bone_lengths [J]`` (each joint's distance from
    its parent, 0 for a root; None when unknown); ``offsets [J, 3]`` (rest offsets from the parent,
    for :func:`~expressive_mocap.dataset.torch_ops.forward_kinematics`; None when unknown);
    ``moving [J]`` (bool: the joints whose distance from their parent changes, i.e. that carry a
    translation of their own: a moving root, or the Bandai-Namco skeleton's hips below its fixed
    root); ``root``: the first moving joint (0 when none moves), whose world positions forward
    kinematics takes as ``root_positions``; ``feet``: ``[[left ankle, left toe], [right ankle,
    right toe]]``, the joints the stored ``contacts`` (left, right) are read from (None when the
    names do not say).
    """

    names: tuple[str, ...]
    parents: np.ndarray
    bone_lengths: np.ndarray | None
    offsets: np.ndarray | None
    moving: np.ndarray
    root: int
    feet: np.ndarray | None

    @property
    def n_joints(self) -> int:
        return len(self.names)

    @property
    def bones(self) -> np.ndarray:
        """``[E, 2]`` int64: (parent, child) of every bone, in the children's order."""
        children = np.flatnonzero(self.parents >= 0)
        return np.stack([self.parents[children], children], axis=1)

    def adjacency(self, self_loops: bool = False) -> np.ndarray:
        """``[J, J]`` float32, symmetric: 1 where two joints share a bone (and on the diagonal with
        ``self_loops``)."""
        a = np.zeros((self.n_joints, self.n_joints), dtype=np.float32)
        bones = self.bones
        a[bones[:, 0], bones[:, 1]] = a[bones[:, 1], bones[:, 0]] = 1.0
        if self_loops:
            a[np.arange(self.n_joints), np.arange(self.n_joints)] = 1.0
        return a

    def edge_index(self) -> np.ndarray:
        """``[2, 2E]`` int64, the form of PyTorch Geometric: every bone both ways, parent to child
        (the first E columns), then child to parent."""
        bones = self.bones
        return np.concatenate([bones.T, bones[:, ::-1].T], axis=1).astype(np.int64)

    def tensors(self, device=None, dtype: torch.dtype = torch.float32) -> dict[str, torch.Tensor]:
        """The arrays as tensors on ``device``: ``parents``, ``edge_index`` (int64), ``adjacency``,
        and ``bone_lengths``, ``offsets`` where known (``dtype``)."""
        out = {
            "parents": torch.as_tensor(self.parents, device=device),
            "edge_index": torch.as_tensor(self.edge_index(), device=device),
            "adjacency": torch.as_tensor(self.adjacency(), dtype=dtype, device=device),
        }
        if self.bone_lengths is not None:
            out["bone_lengths"] = torch.as_tensor(self.bone_lengths, dtype=dtype, device=device)
        if self.offsets is not None:
            out["offsets"] = torch.as_tensor(self.offsets, dtype=dtype, device=device)
        return out


def skeleton_graph(source, frames: int = SAMPLED_FRAMES) -> SkeletonGraph:
    """The :class:`SkeletonGraph` of a dataset (a :class:`~expressive_mocap.dataset.Dataset` or
    its folder) or of a :class:`~expressive_mocap.Skeleton`.

    From a dataset: names and parents from its manifest; bone lengths the median over ``frames``
    rows (evenly spread) of each joint's distance from its parent in the stored ``positions``
    (any ``--positions`` frame: they are all rigid); offsets, when the positions are the world's
    and the rotations are stored, the median of each bone read in its parent's axes
    (``Q_parent^-1 (p_j - p_parent)``; a moving joint's is its median, to be overridden by root
    positions). From a skeleton: its own offsets, and their lengths.
    """
    if isinstance(source, Skeleton):
        return _from_skeleton(source)
    if isinstance(source, (str, os.PathLike)):
        source = load_dataset(source)
    if not isinstance(source, Dataset):
        raise ArgumentError(
            f"argument `source`: expected a Dataset, a dataset's folder or a Skeleton, got {type(source).__name__}"
        )
    if not isinstance(frames, int) or frames < 1:
        raise ArgumentError(f"argument `frames`: expected a positive number of frames, got {frames!r}")
    names = tuple(source.skeleton["names"])
    parents = np.asarray(source.skeleton["parents"], dtype=np.int64)
    rows = np.unique(np.linspace(0, max(int(source.offsets[-1]) - 1, 0), frames).round().astype(np.int64))
    lengths = offsets = None
    moving = np.zeros(len(names), dtype=bool)
    if "positions" in source.kinds and len(rows) and int(source.offsets[-1]) > 0:
        positions = np.asarray(source.positions[rows], dtype=np.float64)
        bones = positions - positions[:, np.maximum(parents, 0)]
        bones[:, parents < 0] = 0.0
        distance = np.linalg.norm(bones, axis=-1)
        lengths = np.median(distance, axis=0)
        spread = distance.max(axis=0) - distance.min(axis=0)
        tolerance = 1e-3 * max(float(lengths.sum()), 1e-9)
        moving = spread > tolerance
        roots = parents < 0
        moving[roots] = np.ptp(positions[:, roots], axis=0).max(axis=-1) > tolerance
        offsets = _offsets(source, rows, positions, parents)
    root = int(np.flatnonzero(moving)[0]) if moving.any() else 0
    return SkeletonGraph(names, parents, lengths, offsets, moving, root, _feet(names, parents))


def _offsets(source: Dataset, rows: np.ndarray, positions: np.ndarray, parents: np.ndarray) -> np.ndarray | None:
    """The rest offsets read from world positions and local rotations (None for other frames)."""
    from ... import ops
    from ...rotations import quat
    from ..representations import decode

    options = source.manifest.get("options", {})
    if options.get("positions", "world") != "world" or "rotations" not in source.kinds:
        return None
    form, _, order = str(options.get("rotations", "quaternion")).partition(":")
    local = decode(np.asarray(source.rotations[rows], dtype=np.float64), form, order or "ZXY")
    world, _ = ops.forward_kinematics(local, np.zeros(local.shape[:-1] + (3,)), parents)
    up = world[:, np.maximum(parents, 0)]
    bones = quat.rotate(quat.conjugate(up), positions - positions[:, np.maximum(parents, 0)])
    bones[:, parents < 0] = positions[:, parents < 0]
    return np.median(bones, axis=0)


def _from_skeleton(skeleton: Skeleton) -> SkeletonGraph:
    parents = np.asarray(skeleton.parents, dtype=np.int64)
    offsets = np.array(skeleton.offsets, dtype=np.float64)
    lengths = np.where(parents < 0, 0.0, np.linalg.norm(offsets, axis=-1))
    moving = np.zeros(len(parents), dtype=bool)
    return SkeletonGraph(skeleton.names, parents, lengths, offsets, moving, 0, _feet(skeleton.names, parents))


def _feet(names, parents: np.ndarray) -> np.ndarray | None:
    from ...body.roles import JointRoles

    try:
        shell = Skeleton(tuple(names), parents, np.zeros((len(names), 3)), tuple(() for _ in names))
        roles = JointRoles.by_names(shell)
    except MocapError:
        return None
    return np.array([[roles.feet[0], roles.toes[0]], [roles.feet[1], roles.toes[1]]], dtype=np.int64)


__all__ = ["SAMPLED_FRAMES", "SkeletonGraph", "skeleton_graph"]
