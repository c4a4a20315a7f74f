"""Stick-figure pictures of motions, side by side: a PNG of poses or an animated GIF.

Orthographic views with Y up: ``"side"`` looks along -X (Z to the right), ``"front"`` looks
along -Z (X to the left, as a mirror would show the actor). Panels share one scale.
"""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path
from typing import Sequence

import numpy as np

from .errors import MocapError
from .io import atomic_write, output_target
from .motion import Motion

_VIEWS = {"side": (2, 1), "front": (0, 1)}


def _segments(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """World positions of bone ends ``[F, B, 2, 3]`` (joint to parent, End Site to its joint)."""
    positions = motion.positions()
    world_rot, _ = motion.fk()
    parents = motion.skeleton.parents
    children = np.flatnonzero(parents >= 0)
    if np.count_nonzero(parents == 0) == 1:
        # A root with one child is a reference node (often on the floor), not a bone end.
        children = children[parents[children] != 0]
    bones = np.stack([positions[:, parents[children]], positions[:, children]], axis=2)
    sites = [(j, off) for j, off in motion.skeleton.end_sites if np.linalg.norm(off) > 0]
    if sites:
        from .quat import rotate

        joints = np.array([j for j, _ in sites])
        tips = positions[:, joints] + rotate(world_rot[:, joints], np.array([off for _, off in sites]))
        bones = np.concatenate([bones, np.stack([positions[:, joints], tips], axis=2)], axis=1)
    return bones, positions


def _project(points: np.ndarray, view: str) -> np.ndarray:
    horizontal, vertical = _VIEWS[view]
    sign = -1.0 if view == "front" else 1.0
    return np.stack([sign * points[..., horizontal], points[..., vertical]], axis=-1)


def _figure(panels: int, width: float = 3.2, height: float = 4.0, stacked: bool = False):
    """A row of panels, or a column when each panel is much wider than tall."""
    import matplotlib

    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt

    shape, size = ((panels, 1), (width, height * panels)) if stacked else ((1, panels), (width * panels, height))
    fig, axes = plt.subplots(*shape, figsize=size, squeeze=False)
    for ax in axes.flat:
        ax.set_aspect("equal")
        ax.axis("off")
    return plt, fig, list(axes.flat)


def _check(motions: Sequence[Motion], titles: Sequence[str] | None, view: str) -> list[str]:
    if not motions:
        raise MocapError("nothing to render: give at least one motion")
    if view not in _VIEWS:
        raise MocapError(f"view must be one of {', '.join(_VIEWS)}, got {view!r}")
    titles = list(titles) if titles is not None else [""] * len(motions)
    if len(titles) != len(motions):
        raise MocapError(f"{len(titles)} titles for {len(motions)} motions")
    return titles


def render_poses(
    motions: Sequence[Motion], path: str | os.PathLike, titles: Sequence[str] | None = None, poses: int = 8, view: str = "side"
) -> None:
    """PNG with one panel per motion, each showing ``poses`` evenly spaced frames where they
    happened (a chronophotograph: a walk spreads along its path), older poses lighter."""
    titles = _check(motions, titles, view)
    all_bones = [_segments(motion)[0] for motion in motions]
    spans = [np.ptp(_project(b.reshape(-1, 3), view), axis=0) for b in all_bones]
    aspect = max(x / max(y, 1e-9) for x, y in spans)
    width = float(np.clip(aspect * 2.6, 2.5, 14.0))
    plt, fig, axes = _figure(len(motions), width=width, height=2.8, stacked=aspect > 2.5)
    for ax, motion, bones, title in zip(axes, motions, all_bones, titles):
        frames = np.linspace(0, motion.n_frames - 1, min(poses, motion.n_frames)).round().astype(int)
        for k, f in enumerate(frames):
            shade = 0.25 + 0.75 * (k + 1) / len(frames)
            for a, b in _project(bones[f], view):
                ax.plot([a[0], b[0]], [a[1], b[1]], color=plt.cm.viridis(1 - shade), lw=1.6, solid_capstyle="round")
        ground = _project(bones.reshape(-1, 3), view)
        ax.axhline(0.0, color="0.7", lw=0.8)
        ax.set_xlim(ground[:, 0].min() - 10, ground[:, 0].max() + 10)
        ax.set_title(title, fontsize=10)
    _save(fig, plt, path)


def render_animation(
    motions: Sequence[Motion], path: str | os.PathLike, titles: Sequence[str] | None = None, view: str = "side", fps: float | None = None
) -> None:
    """Animated GIF, one panel per motion, the camera following each root horizontally.
    Motions are played frame by frame in step; shorter ones hold their last pose."""
    from matplotlib.animation import FuncAnimation, PillowWriter

    titles = _check(motions, titles, view)
    plt, fig, axes = _figure(len(motions))
    projected = []
    for motion in motions:
        bones, positions = _segments(motion)
        flat = _project(bones, view)
        centre = _project(positions[:, 0], view)[:, 0]
        flat[..., 0] -= centre[:, None, None]
        projected.append(flat)
    extent = max(np.abs(p[..., 0]).max() for p in projected) + 5
    top = max(p[..., 1].max() for p in projected) + 5
    lines = []
    for ax, flat, title in zip(axes, projected, titles):
        ax.set_xlim(-extent, extent)
        ax.set_ylim(min(0.0, min(p[..., 1].min() for p in projected)) - 5, top)
        ax.axhline(0.0, color="0.7", lw=0.8)
        ax.set_title(title, fontsize=10)
        lines.append([ax.plot([], [], color="tab:blue", lw=2)[0] for _ in range(flat.shape[1])])
    frames = max(len(p) for p in projected)

    def draw(f: int):
        for flat, panel in zip(projected, lines):
            for (a, b), line in zip(flat[min(f, len(flat) - 1)], panel):
                line.set_data([a[0], b[0]], [a[1], b[1]])
        return [line for panel in lines for line in panel]

    rate = fps or motions[0].fps
    animation = FuncAnimation(fig, draw, frames=frames, blit=True)
    # PillowWriter needs a file name: render into a scratch folder, then write atomically.
    try:
        with tempfile.TemporaryDirectory() as scratch:
            scratch_file = os.path.join(scratch, "animation.gif")
            animation.save(scratch_file, writer=PillowWriter(fps=min(rate, 50)))
            data = Path(scratch_file).read_bytes()
    except OSError as error:  # e.g. the temporary folder is full: say which file was being made, and where
        raise MocapError(f"cannot write {path}: making the GIF in {tempfile.gettempdir()} failed: {error.strerror or error}") from None
    finally:
        plt.close(fig)
    atomic_write(path, data)


def render(motions: Sequence[Motion], path: str | os.PathLike, titles: Sequence[str] | None = None, view: str = "side", **options) -> None:
    """Render to ``path``: a GIF animation if it ends in ``.gif``, otherwise a PNG of poses.
    ``path`` is checked before drawing (:func:`expressive_mocap.io.output_target`)."""
    output_target(path)
    if str(path).lower().endswith(".gif"):
        render_animation(motions, path, titles, view, **options)
    elif str(path).lower().endswith(".png"):
        render_poses(motions, path, titles, view=view, **options)
    else:
        raise MocapError(f"render: the output must end in .png or .gif, got {path}")


def _save(fig, plt, path: str | os.PathLike) -> None:
    buffer = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    atomic_write(path, buffer.getvalue())


def plot_contacts(
    contacts: np.ndarray, frame_time: float, path: str | os.PathLike, title: str = "", labels: Sequence[str] = ("left foot", "right foot")
) -> None:
    """A gait diagram PNG: one row per foot (``contacts bool [F, S]``, rows top to bottom in
    ``labels`` order), a bar for each contact, time in seconds along the bottom."""
    import matplotlib

    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt

    from .features import contact_intervals

    contacts = np.asarray(contacts, dtype=bool)
    if contacts.ndim != 2 or contacts.shape[1] != len(labels):
        raise MocapError(f"plot_contacts: expected contacts [F, {len(labels)}], got {list(contacts.shape)}")
    duration = len(contacts) * frame_time
    fig, ax = plt.subplots(figsize=(float(np.clip(2.0 + 1.1 * duration, 6.0, 16.0)), 0.55 * len(labels) + 1.3))
    colours = ["tab:blue", "tab:orange", "tab:green", "tab:red"]
    for row, intervals in enumerate(contact_intervals(contacts, frame_time)):
        y = len(labels) - 1 - row
        # A frame stands for the frame_time that starts at it, so bars join up with no gaps.
        spans = [(i.start * frame_time, i.seconds) for i in intervals]
        ax.broken_barh(spans, (y - 0.35, 0.7), color=colours[row % len(colours)])
    ax.set_yticks(range(len(labels)), list(reversed(labels)))
    ax.set_xlim(0.0, duration)
    ax.set_ylim(-0.6, len(labels) - 0.4)
    ax.set_xlabel("time (s)")
    if duration <= 30:
        from matplotlib.ticker import MultipleLocator

        ax.xaxis.set_major_locator(MultipleLocator(1.0))  # a grid line a second: steps are countable
    ax.grid(axis="x", color="0.85", lw=0.6)
    ax.set_axisbelow(True)
    for side in ("top", "right"):
        ax.spines[side].set_visible(False)
    ax.set_title(title, fontsize=10, loc="left")
    _save(fig, plt, path)
