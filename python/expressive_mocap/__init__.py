"""expressive-mocap: find, measure and edit the expressive part of human motion capture.

Quaternions are x, y, z, w; arrays are float64 ``[F, J, ...]`` (frames, joints); Y is up;
lengths are in the file's units. See docs/bvh.md for the conventions table.
"""

from typing import TYPE_CHECKING

from ._utils.lazy import lazy_exports

__version__ = "0.1.0"

# Every name loads on first use (PEP 562), so ``import expressive_mocap`` (and the command line's
# start-up: ``--version``, ``info``) loads no NumPy, SciPy or model until something needs it.
_LAZY = {
    "ArgumentError": "errors",
    "BVHError": "errors",
    "Body": "body.body",
    "BodyModel": "decoupling",
    "ClipError": "errors",
    "Dataset": "dataset",
    "DatasetError": "errors",
    "Decomposition": "decoupling",
    "ExaggerationModel": "exaggeration",
    "FEATURE_NAMES": "decoupling.features",
    "JointRoles": "body.roles",
    "MocapError": "errors",
    "Mlp": "decoupling.network",
    "ModelError": "errors",
    "Motion": "motion",
    "ParseError": "errors",
    "Skeleton": "motion",
    "StreamingDecoupler": "decoupling",
    "Take": "body.take",
    "actor_height": "body.body",
    "blend": "decoupling",
    "bvh_bytes": "bvh",
    "contact_intervals": "body.contacts",
    "decompose": "decoupling",
    "dynamic_features": "decoupling.features",
    "euler_to_quat": "ops",
    "exaggerate": "exaggeration",
    "fit_positions": "skeletons.fit",
    "foot_contacts": "body.contacts",
    "forward_kinematics": "ops",
    "forward_kinematics_many": "ops",
    "gait_many": "decoupling.features",
    "get_backend": "backend",
    "load_dataset": "dataset",
    "mix": "decoupling",
    "mlp_forward": "ops",
    "modulate": "decoupling",
    "preprocess": "dataset",
    "quat_to_euler": "ops",
    "read_bvh": "bvh",
    "read_bvh_many": "bvh",
    "rust_available": "backend",
    "set_backend": "backend",
    "use_backend": "backend",
    "write_bvh": "bvh",
}

if TYPE_CHECKING:  # what the names are, for type checkers and editors
    from .backend import get_backend, rust_available, set_backend, use_backend
    from .body.body import Body, actor_height
    from .body.contacts import contact_intervals, foot_contacts
    from .body.roles import JointRoles
    from .body.take import Take
    from .bvh import bvh_bytes, read_bvh, read_bvh_many, write_bvh
    from .dataset import Dataset, load_dataset, preprocess
    from .decoupling import BodyModel, Decomposition, StreamingDecoupler, blend, decompose, mix, modulate
    from .decoupling.features import FEATURE_NAMES, dynamic_features, gait_many
    from .decoupling.network import Mlp
    from .errors import ArgumentError, BVHError, ClipError, DatasetError, MocapError, ModelError, ParseError
    from .exaggeration import ExaggerationModel, exaggerate
    from .motion import Motion, Skeleton
    from .ops import euler_to_quat, forward_kinematics, forward_kinematics_many, mlp_forward, quat_to_euler
    from .skeletons.fit import fit_positions

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
    "fit_positions",
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
