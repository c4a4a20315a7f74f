"""The decoupling method of Boehs, Vieira & Pereira ("Decoupling Expressiveness and
Body-Mechanics in Human Motion"): a motion's rotations split into an expressive component and
the body mechanics a neutral performer would show with the same dynamics.

- :mod:`.algebra`: the split ``O = E* B'`` (:func:`decompose`, :func:`decompose_many`, the
  step shared by batch, dataset preprocessing and streaming);
- :mod:`.body_model`: :class:`BodyModel`, the body-mechanics model, and its file format;
- :mod:`.network`: :class:`Mlp`, the dense network inside a body model;
- :mod:`.training`: training the network (L-BFGS) and a body model from neutral clips;
- :mod:`.edits`: modulation, source mixing and asynchronous blending;
- :mod:`.streaming`: :class:`StreamingDecoupler`, one frame at a time;
- :mod:`.features`: the dynamic features the model reads (their foot contacts come from
  :mod:`expressive_mocap.body.contacts`, shared with exaggeration and preprocessing).
"""

from __future__ import annotations

from .._utils.lazy import lazy_exports

# Submodules load on first use: ``import expressive_mocap`` needs only the network.
_LAZY = {
    "EXPONENT": "algebra",
    "GAIN": "algebra",
    "BlendAlignment": "edits",
    "BodyMechanicsModel": "algebra",
    "BodyModel": "body_model",
    "Decomposition": "algebra",
    "Layer": "network",
    "Mlp": "network",
    "StreamingDecoupler": "streaming",
    "blend": "edits",
    "blend_alignment": "edits",
    "decompose": "algebra",
    "decompose_many": "algebra",
    "mix": "edits",
    "modulate": "edits",
    "poor_fit": "body_model",
    "split": "algebra",
    "split_from_features": "algebra",
    "train_body_model": "training",
}


__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())


__all__ = [
    "EXPONENT",
    "GAIN",
    "BlendAlignment",
    "BodyMechanicsModel",
    "BodyModel",
    "Decomposition",
    "Layer",
    "Mlp",
    "StreamingDecoupler",
    "blend",
    "blend_alignment",
    "decompose",
    "decompose_many",
    "mix",
    "modulate",
    "poor_fit",
    "split",
    "split_from_features",
    "train_body_model",
]
