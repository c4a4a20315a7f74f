"""PyTorch operations for training on a preprocessed dataset: rotation conversions in the
package's conventions, forward kinematics, the skeleton as a graph and small loss terms; all
batched over any leading axes and differentiable. Importing this subpackage imports torch
(``pip install '.[torch]'``); ``expressive_mocap`` and ``expressive_mocap.dataset`` do not.

- :mod:`.rotations`: quaternions (x, y, z, w), 6D (the matrix's first two columns, column after
  column), matrices and rotation vectors, each way through the matrix or the quaternion, and the
  twins of :func:`~expressive_mocap.dataset.representations.encode` / ``decode``;
- :mod:`.kinematics`: :func:`forward_kinematics`, the twin of the package's kernel;
- :mod:`.graph`: :func:`skeleton_graph` of a dataset or skeleton (parents, bone lengths, offsets,
  adjacency, edge index);
- :mod:`.losses`: :func:`velocity_loss`, :func:`foot_contact_loss`, :func:`finite_velocities`.

See docs/torch.md.
"""

from .graph import SkeletonGraph, skeleton_graph
from .kinematics import forward_kinematics
from .losses import finite_velocities, foot_contact_loss, velocity_loss
from .rotations import (
    FORMS,
    axis_angle_to_matrix,
    axis_angle_to_quat,
    euler_to_quat,
    form_size,
    from_quat,
    matrix_to_axis_angle,
    matrix_to_euler,
    matrix_to_quat,
    matrix_to_sixd,
    quat_conjugate,
    quat_mul,
    quat_normalize,
    quat_rotate,
    quat_to_axis_angle,
    quat_to_euler,
    quat_to_matrix,
    quat_to_sixd,
    sixd_to_matrix,
    sixd_to_quat,
    to_matrix,
    to_quat,
)

__all__ = [
    "FORMS",
    "SkeletonGraph",
    "axis_angle_to_matrix",
    "axis_angle_to_quat",
    "euler_to_quat",
    "finite_velocities",
    "foot_contact_loss",
    "form_size",
    "forward_kinematics",
    "from_quat",
    "matrix_to_axis_angle",
    "matrix_to_euler",
    "matrix_to_quat",
    "matrix_to_sixd",
    "quat_conjugate",
    "quat_mul",
    "quat_normalize",
    "quat_rotate",
    "quat_to_axis_angle",
    "quat_to_euler",
    "quat_to_matrix",
    "quat_to_sixd",
    "sixd_to_matrix",
    "sixd_to_quat",
    "skeleton_graph",
    "to_matrix",
    "to_quat",
    "velocity_loss",
]
