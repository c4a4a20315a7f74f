"""Shared fixtures: the synthetic test files, the Bandai-Namco data (skipped with a reason
when absent, a failure under CI=true), both kernel backends, and an independent SciPy
reference for decoding BVH channels."""

from __future__ import annotations

import os
import subprocess
import threading
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em

DATA = Path(__file__).parent / "data"
REPO = Path(__file__).resolve().parent.parent
SHARED_DATA = REPO.parent / "shared" / "data"
CACHE = Path(os.environ.get("EXPRESSIVE_MOCAP_DATA_CACHE", Path.home() / ".cache" / "motion-data"))

BACKENDS = ["numpy"] + (["rust"] if em.rust_available() else [])


@pytest.fixture(params=BACKENDS)
def backend(request):
    """Run the test once per available kernel backend."""
    with em.use_backend(request.param):
        yield request.param


@pytest.fixture
def mixed_path() -> Path:
    """A small hand-written file: six rotation orders, 0-6 channels, position channels after
    rotations, End Sites, a ':' and a space in joint names, exponents."""
    return DATA / "mixed_orders.bvh"


def _unpacked_dataset() -> Path | None:
    unpack = SHARED_DATA / "unpack"
    if not unpack.exists():
        return None
    result = subprocess.run([str(unpack), str(CACHE)], capture_output=True, text=True, check=True)
    return Path(result.stdout.strip().splitlines()[-1])


def _dataset_dir(number: int) -> Path:
    dataset = _unpacked_dataset()
    if dataset is None:
        reason = f"the Bandai-Namco archives are not at {SHARED_DATA} (they come with the project's shared/ folder)"
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI=true but {reason}")
        pytest.skip(reason)
    return dataset / f"Bandai-Namco-Research-Motiondataset-{number}" / "data"


@pytest.fixture(scope="session")
def bandai2_dir() -> Path:
    """dataset-2 clips (unpacked once into ~/.cache/motion-data)."""
    return _dataset_dir(2)


@pytest.fixture(scope="session")
def walks_people(bandai2_dir) -> list:
    """Dataset-2's walks, take ``p`` of exhausted / normal / active as person ``p``, takes 1-8."""
    styles = ("exhausted", "normal", "active")  # intensities 1, 2, 3
    return [[em.read_bvh(bandai2_dir / f"dataset-2_walk_{s}_{p:03d}.bvh") for s in styles] for p in range(1, 9)]


@pytest.fixture(scope="session")
def walks_model(walks_people):
    """The exaggeration model of :func:`walks_people` at intensities 1, 2, 3 (trained once)."""
    from expressive_mocap.exaggeration import train

    return train(walks_people, (1.0, 2.0, 3.0))


@pytest.fixture(scope="session")
def bandai1_dir() -> Path:
    """dataset-1 clips."""
    return _dataset_dir(1)


@pytest.fixture(scope="session")
def other_dir() -> Path:
    """Real BVH files on other skeletons (CMU, Xia-style), beside the Bandai-Namco archives."""
    other = SHARED_DATA / "other"
    if not other.is_dir():
        reason = f"the non-Bandai files are not at {other} (they come with the project's shared/ folder)"
        if os.environ.get("CI") == "true":
            pytest.fail(f"CI=true but {reason}")
        pytest.skip(reason)
    return other


@pytest.fixture(scope="module")
def mixed_zip(bandai2_dir, other_dir, tmp_path_factory) -> tuple[Path, dict[str, Path]]:
    """3 Bandai clips at 30 fps and 2 CMU clips at 120 fps, the CMU clips first by name (see
    mixed_archives.py)."""
    from mixed_archives import bandai_members, cmu_members, zip_of

    members = {**bandai_members(bandai2_dir), **cmu_members(other_dir)}
    return zip_of(tmp_path_factory.mktemp("mixed") / "mixed.zip", members), members


def bvh_values(path: Path) -> np.ndarray:
    """The MOTION numbers of a file, read with plain NumPy (independent of the package)."""
    text = Path(path).read_text()
    block = text.split("Frame Time:", 1)[1].split("\n", 1)[1]
    return np.loadtxt(block.splitlines(), ndmin=2)


def scipy_fk(skeleton: em.Skeleton, values: np.ndarray) -> tuple[list[Rotation], np.ndarray]:
    """World rotations (one SciPy Rotation of every frame per joint) and positions ``[F, J, 3]``
    from channel values, composed with SciPy: per joint the rotation channels in written order
    (intrinsic, upper case), position channels replacing the offset components they name, parent
    x child."""
    frames = len(values)
    world_rot: list[Rotation] = []
    world_pos = np.zeros((frames, skeleton.n_joints, 3))
    column = 0
    for j, channels in enumerate(skeleton.channels):
        offset = np.tile(skeleton.offsets[j], (frames, 1))
        axes, angles = "", []
        for name in channels:
            if name.endswith("rotation"):
                axes += name[0]
                angles.append(values[:, column])
            else:
                offset[:, "XYZ".index(name[0])] = values[:, column]
            column += 1
        local = Rotation.from_euler(axes, np.stack(angles, 1), degrees=True) if axes else Rotation.identity(frames)
        parent = skeleton.parents[j]
        if parent < 0:
            world_rot.append(local)
            world_pos[:, j] = offset
        else:
            world_rot.append(world_rot[parent] * local)
            world_pos[:, j] = world_pos[:, parent] + world_rot[parent].apply(offset)
    return world_rot, world_pos


def scipy_positions(skeleton: em.Skeleton, values: np.ndarray) -> np.ndarray:
    """World joint positions ``[F, J, 3]`` from channel values (see :func:`scipy_fk`)."""
    return scipy_fk(skeleton, values)[1]


def forward_lean(motion: em.Motion, neck: str, legs: tuple[str, str]) -> float:
    """Mean angle (degrees, SciPy FK) of the line from the joint "Hips" to ``neck`` from
    vertical, towards the facing (the horizontal normal of the line between the upper ``legs``)."""
    p = scipy_positions(motion.skeleton, motion.channel_values())
    at = motion.skeleton.index
    trunk = p[:, at(neck)] - p[:, at("Hips")]
    side = p[:, at(legs[0])] - p[:, at(legs[1])]
    side[:, 1] = 0.0
    forward = np.cross(side, [0.0, 1.0, 0.0])
    forward /= np.linalg.norm(forward, axis=1, keepdims=True)
    return float(np.degrees(np.arctan2(np.sum(trunk * forward, axis=1), trunk[:, 1])).mean())


def stick_walker(hips, left_foot, right_foot, fps: float = 30.0, prefix: str = "") -> em.Motion:
    """A 9-joint CMU-named figure (``prefix`` e.g. "mixamorig:") whose hips and ankles go
    exactly where told: ``hips``, ``left_foot``, ``right_foot`` are world positions ``[F, 3]``
    (cm). Rotations are identity; the toes sit 10 cm ahead of the ankles at the same height.
    Facing +Z, left is +X; rest hips 90 cm above the origin, spine-to-head chain 50 cm: the
    actor is 140 cm tall."""
    names = ["Hips", "Spine", "Head", "LeftUpLeg", "LeftFoot", "LeftToeBase", "RightUpLeg", "RightFoot", "RightToeBase"]
    parents = [-1, 0, 1, 0, 3, 4, 0, 6, 7]
    offsets = np.array(
        [
            [0, 90, 0],
            [0, 20, 0],
            [0, 30, 0],
            [10, -5, 0],
            [0, -80, 0],
            [0, 0, 10],
            [-10, -5, 0],
            [0, -80, 0],
            [0, 0, 10],
        ],
        dtype=float,
    )
    six = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    skeleton = em.Skeleton(tuple(prefix + n for n in names), parents, offsets, (six,) * len(names))
    hips = np.asarray(hips, dtype=float)
    translations = np.broadcast_to(offsets, (len(hips), len(names), 3)).copy()
    translations[:, 0] = hips
    translations[:, 4] = np.asarray(left_foot, dtype=float) - hips - offsets[3]
    translations[:, 7] = np.asarray(right_foot, dtype=float) - hips - offsets[6]
    rotations = np.zeros((len(hips), len(names), 4))
    rotations[..., 3] = 1.0
    return em.Motion(skeleton, rotations, translations, 1.0 / fps)


def straight_walker(frames=40, velocity=(0.0, 0.0, 140.0), fps=30.0):
    """Hips 90 cm up moving at a constant ``velocity`` (cm/s), facing +Z, feet on the floor."""
    t = np.arange(frames)[:, None] / fps
    hips = np.array([0.0, 90.0, 0.0]) + t * np.array(velocity)
    feet = hips * [1, 0, 1]
    return stick_walker(hips, feet + [10, 0, 0], feet - [10, 0, 0], fps=fps)


def returns_within(seconds: float, call):
    """``call()``'s result or exception, failing the test if it has not returned in time (a read
    of a FIFO blocks until a writer comes)."""
    outcome: dict = {}

    def run():
        try:
            outcome["value"] = call()
        except BaseException as error:  # handed back to the test
            outcome["error"] = error

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    thread.join(seconds)
    assert not thread.is_alive(), f"still blocked after {seconds} s"
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


class FixedFloor:
    """The model with the floor fixed, as the streaming decoupler uses it."""

    def __init__(self, model, floor):
        self.model, self.floor = model, floor

    def predict(self, motion):
        return self.model.predict(motion, floor=self.floor)

    def predict_streamed(self, motion, window: int | None = None):
        """Each frame's prediction as a stream keeping ``window`` frames (None: all) makes it: the
        spine carried onto the pelvis posture of the frames it holds."""
        from expressive_mocap.decoupling.pelvis import mean_posture

        features, pelvis = self.model.features(motion, floor=self.floor), self.model.pelvis
        rotations = motion.rotations
        return np.concatenate(
            [
                self.model.predict_from_features(
                    rotations[f : f + 1],
                    features[f : f + 1],
                    None
                    if pelvis is None
                    else mean_posture(rotations[max(0, f + 1 - (window or f + 1)) : f + 1], pelvis.path),
                )
                for f in range(len(rotations))
            ]
        )
