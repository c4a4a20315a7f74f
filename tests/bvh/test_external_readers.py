"""Files written by write_bvh must import the same way in other people's BVH readers.

Blender's importer (bpy) and bvhio each rebuild world joint positions from the file we wrote;
they must match Motion.positions() of the motion we wrote. Both readers compute in float32.

Marker `blender` (for pyproject's markers): "imports a written file with Blender's BVH importer (bpy)".
"""

from __future__ import annotations

import importlib
import os

import numpy as np
import pytest

import expressive_mocap as em

INSTALL = {
    # bpy wheels exist for CPython 3.11 on x86-64 Linux; they pin numpy<2.
    "bpy": "pip install bpy==4.5.4; on Debian also apt-get install libx11-6 libxrender1 libxfixes3 libxi6 "
    "libxkbcommon0 libsm6 libgl1",
    "bvhio": "pip install bvhio==1.5.4",
}

# Largest error allowed, relative to the largest coordinate: float32 rounding grows with distance
# from the origin, not with the skeleton's size. Measured: at most 4e-7, for both readers.
REL_TOL = 2e-6


def need(module: str):
    """Import an external reader: skip without it, but fail under CI=true."""
    try:
        return importlib.import_module(module)
    except ImportError as exc:  # also a missing shared library, e.g. libX11.so.6 for bpy
        message = f"{module} is not importable ({exc}); {INSTALL[module]}"
        if os.environ.get("CI") == "true":
            pytest.fail(message, pytrace=False)
        pytest.skip(message)


def blender_positions(path, motion, scale=0.01):
    """Joint names and world positions [F, J, 3] from Blender's importer, in BVH axes and units."""
    bpy = need("bpy")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_anim.bvh(
        filepath=str(path),
        axis_forward="-Z",
        axis_up="Y",
        global_scale=scale,
        rotate_mode="NATIVE",
        update_scene_fps=True,
        frame_start=1,
    )
    scene, armature, n_frames = bpy.context.scene, bpy.context.object, motion.n_frames
    assert armature.animation_data.action.frame_range[:] == pytest.approx((1, n_frames))
    assert scene.render.fps / scene.render.fps_base == pytest.approx(1 / motion.frame_time)
    # Bones run from a joint to its child or End Site, so a pose bone's head is the joint.
    bones = armature.pose.bones
    out = np.empty((n_frames, len(bones), 3))
    for f in range(n_frames):
        scene.frame_set(f + 1)  # BVH frame 0 is Blender frame frame_start
        out[f] = [armature.matrix_world @ b.head for b in bones]
    # Blender is Z-up: blender (x, y, z) = bvh (x, -z, y).
    return [b.name for b in bones], np.stack([out[..., 0], out[..., 2], -out[..., 1]], -1) / scale


def bvhio_positions(path, motion):
    """Joint names and world positions [F, J, 3] from bvhio."""
    bvhio = need("bvhio")
    root, n_frames = bvhio.readAsHierarchy(str(path)), motion.n_frames
    assert root.getKeyframeRange() == (0, n_frames - 1)
    joints = [joint for joint, _, _ in root.layout()]
    out = np.empty((n_frames, len(joints), 3))
    for f in range(n_frames):
        root.loadPose(f)
        out[f] = [tuple(j.PositionWorld) for j in joints]
    return [j.Name for j in joints], out


READERS = [
    pytest.param(blender_positions, id="blender", marks=pytest.mark.blender),
    pytest.param(bvhio_positions, id="bvhio"),
]


def read_back(reader, motion, tmp_path):
    """Write the motion, then read it with an external reader: joint names, world positions."""
    path = tmp_path / "written.bvh"
    em.write_bvh(motion, path)
    return reader(path, motion)


def assert_positions_match(got, motion):
    expected = motion.positions()
    error, tolerance = np.abs(got - expected).max(), REL_TOL * np.abs(expected).max()
    assert error <= tolerance, f"max error {error:.3g} > {tolerance:.3g} (file units)"


# Every rotation order, position channels mixed in among rotations, End Sites not at the origin.
# Only what Blender reads: it needs 0 or 3 rotation channels per joint, zeroes the position
# components a joint has no channel for, and turns spaces in names into underscores.
MIXED = """HIERARCHY
ROOT pelvis
{
  OFFSET 1.0 90.0 -2.0
  CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation
  JOINT spine
  {
    OFFSET 0.0 12.0 1.5
    CHANNELS 3 Zrotation Xrotation Yrotation
    JOINT head
    {
      OFFSET 0.5 30.0 0.0
      CHANNELS 3 Yrotation Zrotation Xrotation
      End Site
      {
        OFFSET 0.0 15.0 2.0
      }
    }
    JOINT arm
    {
      OFFSET 18.0 25.0 -1.0
      CHANNELS 3 Zrotation Yrotation Xrotation
      JOINT hand
      {
        OFFSET 28.0 0.0 3.0
        CHANNELS 6 Zrotation Xposition Yrotation Yposition Xrotation Zposition
        End Site
        {
          OFFSET 9.0 0.0 0.0
        }
      }
    }
  }
  JOINT leg
  {
    OFFSET -9.0 -4.0 0.0
    CHANNELS 3 Xrotation Zrotation Yrotation
    JOINT foot
    {
      OFFSET 0.0 -45.0 2.0
      CHANNELS 3 Yrotation Xrotation Zrotation
      End Site
      {
        OFFSET 0.0 -5.0 12.0
      }
    }
  }
}
MOTION
Frames: 5
Frame Time: 0.04
"""


def mixed_motion_text() -> str:
    rng = np.random.default_rng(7)
    rows = rng.uniform(-170.0, 170.0, size=(5, 27))  # large angles: a wrong order cannot hide
    rows[:, 0:3] = rng.uniform(-50.0, 50.0, size=(5, 3))  # root translation
    rows[:, [16, 18, 20]] = rng.uniform(20.0, 30.0, size=(5, 3))  # hand's position channels
    return MIXED + "".join(" ".join(f"{v:.4f}" for v in row) + "\n" for row in rows)


@pytest.mark.real_data
@pytest.mark.parametrize("reader", READERS)
def test_real_clip_imports_the_same(reader, bandai2_dir, tmp_path):
    motion = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh")[100:140]
    names, got = read_back(reader, motion, tmp_path)
    assert names == list(motion.skeleton.names)
    assert_positions_match(got, motion)


@pytest.mark.parametrize("reader", READERS)
def test_mixed_rotation_orders_import_the_same(reader, tmp_path):
    source = tmp_path / "mixed.bvh"
    source.write_text(mixed_motion_text())
    motion = em.read_bvh(source)
    names, got = read_back(reader, motion, tmp_path)
    assert names == list(motion.skeleton.names)
    assert_positions_match(got, motion)


def test_partial_channel_sets_import_the_same_in_bvhio(mixed_path, tmp_path):
    """Joints with 0, 1 or 2 channels, which Blender's importer rejects."""
    motion = em.read_bvh(mixed_path)
    names, got = read_back(bvhio_positions, motion, tmp_path)
    assert names == [name.split()[0] for name in motion.skeleton.names]  # bvhio keeps the first word
    assert_positions_match(got, motion)
