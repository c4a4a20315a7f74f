"""An independent BVH reader and forward kinematics for the experiments' measurements: the hierarchy
parsed token by token, the MOTION numbers read with NumPy, rotation channels composed
intrinsically in written order with SciPy (position channels replace the offset components they
name), parent x child. Never the package's own reader, Euler kernels or FK, which are what the
experiments measure.

    from independent import read_fk
    fk = read_fk(path)   # fk.names, fk.rotations (a SciPy Rotation per joint), fk.positions [F, J, 3], fk.frame_time
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["FK", "parse_bvh", "read_fk", "scipy_fk"]


class FK(NamedTuple):
    names: list[str]
    rotations: list[Rotation]  # world, one Rotation of every frame per joint
    positions: np.ndarray  # [F, J, 3] world, file units
    frame_time: float


def parse_bvh(text: str) -> tuple[list[str], list[int], np.ndarray, list[list[str]], np.ndarray, float]:
    """Names, parents, offsets ``[J, 3]``, channel names per joint, the MOTION numbers and the
    frame time (End Sites skipped)."""
    head, motion = text.split("MOTION", 1)
    names: list[str] = []
    parents: list[int] = []
    offsets: list[list[float]] = []
    channels: list[list[str]] = []
    stack: list[int] = []
    in_site = False
    tokens = head.split()
    i = 0
    while i < len(tokens):
        t = tokens[i]
        if t in ("ROOT", "JOINT"):
            names.append(tokens[i + 1])
            parents.append(stack[-1] if stack else -1)
            i += 2
            continue
        if t == "End":
            in_site = True
            i += 2
            continue
        if t == "{":
            if not in_site:
                stack.append(len(names) - 1)
        elif t == "}":
            if in_site:
                in_site = False
            else:
                stack.pop()
        elif t == "OFFSET":
            if not in_site:
                offsets.append([float(v) for v in tokens[i + 1 : i + 4]])
            i += 4
            continue
        elif t == "CHANNELS":
            n = int(tokens[i + 1])
            channels.append(tokens[i + 2 : i + 2 + n])
            i += 2 + n
            continue
        i += 1
    timing, numbers = motion.split("Frame Time:", 1)[1].split("\n", 1)
    values = np.loadtxt(io.StringIO(numbers), ndmin=2)
    return names, parents, np.array(offsets), channels, values, float(timing)


def scipy_fk(text: str) -> tuple[list[str], list[Rotation], np.ndarray]:
    """Joint names, world rotations (per joint, every frame) and positions ``[F, J, 3]`` of BVH ``text``."""
    fk = _fk(text)
    return fk.names, fk.rotations, fk.positions


def read_fk(path: str | Path) -> FK:
    """:class:`FK` of a BVH file."""
    return _fk(Path(path).read_text())


def _fk(text: str) -> FK:
    names, parents, offsets, channels, values, frame_time = parse_bvh(text)
    frames = len(values)
    world_rot: list[Rotation] = []
    world_pos = np.zeros((frames, len(names), 3))
    column = 0
    for j, chans in enumerate(channels):
        offset = np.tile(offsets[j], (frames, 1))
        axes, angles = "", []
        for name in chans:
            if name.lower().endswith("rotation"):
                axes += name[0].upper()
                angles.append(values[:, column])
            else:
                offset[:, "XYZ".index(name[0].upper())] = values[:, column]
            column += 1
        local = Rotation.from_euler(axes, np.stack(angles, 1), degrees=True) if axes else Rotation.identity(frames)
        if parents[j] < 0:
            world_rot.append(local)
            world_pos[:, j] = offset
        else:
            world_rot.append(world_rot[parents[j]] * local)
            world_pos[:, j] = world_pos[:, parents[j]] + world_rot[parents[j]].apply(offset)
    return FK(names, world_rot, world_pos, frame_time)
