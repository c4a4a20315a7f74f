"""Motion moved between skeletons (what each skeleton is lives in :mod:`expressive_mocap.body`):

- :mod:`.retargeting`: a motion moved onto another skeleton (:func:`retarget`);
- :mod:`.twist`: how a bone faces about itself, read from joint positions;
- :mod:`.mirror`: a motion mirrored left for right (:func:`mirror`);
- :mod:`.fit`: joint positions (:mod:`.layouts`) fitted as a motion on a chosen skeleton
  (:func:`fit_positions`);
- :mod:`.smpl`: SMPL-family parameter files (AMASS) on the user's body model (:func:`read_smpl`);
- :mod:`.synthetic`: the demo's walk on six synthetic skeletons, with their ground truth.
"""

from __future__ import annotations

from .._utils.lazy import lazy_exports

_LAZY = {
    "LAYOUTS": "layouts",
    "Rig": "retargeting",
    "fit_positions": "fit",
    "retarget": "retargeting",
    "mirror": "mirror",
    "read_smpl": "smpl",
    "RIGS": "synthetic",
    "synthetic_skeleton": "synthetic",
    "synthetic_walk": "synthetic",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

__all__ = [
    "LAYOUTS",
    "RIGS",
    "fit_positions",
    "Rig",
    "mirror",
    "read_smpl",
    "retarget",
    "synthetic_skeleton",
    "synthetic_walk",
]
