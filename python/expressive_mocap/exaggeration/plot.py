"""The ranking shown: as a text table and as a bar plot like the paper's Figure 1."""

from __future__ import annotations

import io
import os
from typing import TYPE_CHECKING

import numpy as np

from .._utils.files import atomic_write

if TYPE_CHECKING:
    from .model import ExaggerationModel


def ranking_table(model: ExaggerationModel, top: int | None = None) -> str:
    """The ranking as text: DOFs (most expressive first, key ones marked) then joints."""
    order = np.argsort(-model.overall)
    cumulative = np.cumsum(model.overall[order])
    lines = [f"{'DOF':<18} {'E':>7} {'cum.':>6}  key"]
    for n, d in enumerate(order[: top or len(order)]):
        lines.append(
            f"{model.dof_names[d]:<18} {model.overall[d]:7.4f} {cumulative[n]:6.3f}  {'*' if model.key[d] else ''}"
        )
    lines.append("")
    lines.append(f"{'joint':<18} {'E':>7}")
    for name, value in sorted(model.joint_expressiveness().items(), key=lambda kv: -kv[1]):
        lines.append(f"{name:<18} {value:7.4f} {'#' * int(round(value * 60))}")
    zero = model.zero_weight_joints
    if zero:
        lines.append(f"weight 0 (no bone below them, never key features): {', '.join(zero)}")
    share = model.training.share
    lines.append(
        f"{int(model.key.sum())} key DOFs of {model.n_dofs} ({model.key.mean():.0%}) at share {share:g}; "
        f"basis: {model.basis.shape[1]} of {model.basis.shape[0]} vectors ({model.energy:.1%} of the energy); "
        f"{model.expressiveness.shape[0]} person(s), intensities {', '.join(f'{k:g}' for k in model.levels)}"
    )
    return "\n".join(lines)


def plot_ranking(model: ExaggerationModel, path: str | os.PathLike, title: str = "") -> None:
    """A bar plot like the paper's Figure 1 (bottom): expressiveness per DOF, grouped by joint in
    skeleton order, key DOFs dark; below it the per-joint sums. PNG, written atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(12, 6.5))
    x = np.arange(model.n_dofs)
    top.bar(x, model.overall, color=np.where(model.key, "tab:red", "0.7"), width=0.85)
    top.set_xticks(np.arange(1, model.n_dofs, 3), list(model.joint_names), rotation=70, fontsize=7)
    top.set_ylabel("expressiveness E (per DOF)")
    top.set_title(title or "expressiveness per DOF (red: key features)", fontsize=10, loc="left")
    per_joint = model.joint_expressiveness()
    names = list(per_joint)
    key_joints = {
        model.joint_of(d) if not model.dof_names[d].endswith("height") else "Hips.height"
        for d in np.flatnonzero(model.key)
    }
    colours = ["tab:red" if n in key_joints else "0.7" for n in names]
    bottom.bar(np.arange(len(names)), list(per_joint.values()), color=colours)
    bottom.set_xticks(np.arange(len(names)), names, rotation=70, fontsize=7)
    bottom.set_ylabel("expressiveness per joint")
    for ax in (top, bottom):
        for side in ("top", "right"):
            ax.spines[side].set_visible(False)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    plt.close(fig)
    atomic_write(path, buffer.getvalue())


__all__ = ["plot_ranking", "ranking_table"]
