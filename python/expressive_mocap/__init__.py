"""expressive-mocap: find, measure and edit the expressive part of human motion capture.

Quaternions are x, y, z, w; arrays are float64 ``[F, J, ...]`` (frames, joints); Y is up;
lengths are in the file's units. See docs/bvh.md for the conventions table.
"""

from ._utils.lazy import lazy_exports
from .backend import get_backend, rust_available, set_backend, use_backend
from .body.body import Body, actor_height
from .body.contacts import contact_intervals, foot_contacts
from .body.roles import JointRoles
from .body.take import Take
from .bvh import bvh_bytes, read_bvh, read_bvh_many, write_bvh
from .decoupling.features import FEATURE_NAMES, dynamic_features, gait_many
from .decoupling.network import Mlp
from .errors import ArgumentError, BVHError, ClipError, DatasetError, MocapError, ModelError, ParseError
from .motion import Motion, Skeleton
from .ops import euler_to_quat, forward_kinematics, forward_kinematics_many, mlp_forward, quat_to_euler

__version__ = "0.1.0"

# Heavier parts load on first use, so ``import expressive_mocap`` stays as cheap as reading BVH.
_LAZY = {
    "BodyModel": "decoupling",
    "Dataset": "dataset",
    "Decomposition": "decoupling",
    "ExaggerationModel": "exaggeration",
    "StreamingDecoupler": "decoupling",
    "blend": "decoupling",
    "decompose": "decoupling",
    "exaggerate": "exaggeration",
    "load_dataset": "dataset",
    "mix": "decoupling",
    "modulate": "decoupling",
    "preprocess": "dataset",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())


__all__ = [
    "ArgumentError",
    "ClipError",
    "DatasetError",
    "ModelError",
    "ParseError",
    "StreamingDecoupler",
    "blend",
    "exaggerate",
    "mix",
    "modulate",
    "preprocess",
    "BVHError",
    "Body",
    "BodyModel",
    "Dataset",
    "Decomposition",
    "ExaggerationModel",
    "FEATURE_NAMES",
    "JointRoles",
    "MocapError",
    "Mlp",
    "Motion",
    "Skeleton",
    "Take",
    "__version__",
    "actor_height",
    "bvh_bytes",
    "contact_intervals",
    "decompose",
    "dynamic_features",
    "euler_to_quat",
    "foot_contacts",
    "gait_many",
    "forward_kinematics",
    "forward_kinematics_many",
    "get_backend",
    "load_dataset",
    "mlp_forward",
    "quat_to_euler",
    "read_bvh",
    "read_bvh_many",
    "rust_available",
    "set_backend",
    "use_backend",
    "write_bvh",
]
