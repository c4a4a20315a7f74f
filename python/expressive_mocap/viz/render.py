"""Stick-figure pictures of motions, side by side: a PNG of poses or an animated GIF.

Orthographic views with Y up, named after the walker, not the world: ``"side"`` looks at the
walker's left side, its direction of travel to the right; ``"front"`` looks at its face, its
left on the picture's left (as a mirror would show the actor). The heading is the hips' travel
from the first frame to the last or, where they barely travel, the facing of the line between
the upper legs (:func:`heading`). Sizes (margins, line widths) follow the figure's own size, so
a file in metres draws as one in centimetres; GIFs play in real time whatever the frame rate.
"""

from __future__ import annotations

import io
import math
import os
import sys
from collections.abc import Sequence
from typing import Literal

import numpy as np

from .._utils.files import atomic_write, output_target
from .._utils.progress import Progress
from ..body.body import Body
from ..body.take import Take
from ..errors import ArgumentError, MocapError
from ..motion import Motion

VIEWS = ("side", "front")
View = Literal["side", "front"]
MARGIN = 0.06  # of the figure's height, around every panel
MIN_GIF_DELAY = 0.02  # s: browsers play shorter GIF frame delays as 0.1 s


def heading(motion: Motion | Take) -> np.ndarray:
    """The walker's forward direction, a horizontal unit vector ``[3]``: the hips' travel from the
    first frame to the last, or their facing where they barely travel (the yaw of
    :func:`~expressive_mocap.exaggeration.cycle_heading` over the whole clip); +Z when the
    skeleton's hips and upper legs cannot be told by name."""
    from ..exaggeration import Cycle, cycle_heading

    take = Take.of(motion)
    try:
        _ = take.body.roles
    except MocapError:
        return np.array([0.0, 0.0, 1.0])
    yaw = np.radians(cycle_heading(take, Cycle(0, take.motion.n_frames - 1)))
    return np.array([np.sin(yaw), 0.0, np.cos(yaw)])


def _horizontal_axis(forward: np.ndarray, view: str) -> np.ndarray:
    """The world direction drawn to the right: forward in the side view, the walker's right in the
    (mirrored) front view."""
    left = np.array([forward[2], 0.0, -forward[0]])  # forward turned 90 degrees about +Y
    return forward if view == "side" else -left


def _segments(take: Take) -> tuple[np.ndarray, np.ndarray]:
    """World positions of bone ends ``[F, B, 2, 3]`` (joint to parent, End Site to its joint)."""
    motion = take.motion
    world_rot, positions = take.fk
    parents = motion.skeleton.parents
    children = np.flatnonzero(parents >= 0)
    if np.count_nonzero(parents == 0) == 1:
        # A root with one child is a reference node (often on the floor), not a bone end.
        children = children[parents[children] != 0]
    bones = np.stack([positions[:, parents[children]], positions[:, children]], axis=2)
    sites = [(j, off) for j, off in motion.skeleton.end_sites if np.linalg.norm(off) > 0]
    if sites:
        from ..rotations.quat import rotate

        joints = np.array([j for j, _ in sites])
        tips = positions[:, joints] + rotate(world_rot[:, joints], np.array([off for _, off in sites]))
        bones = np.concatenate([bones, np.stack([positions[:, joints], tips], axis=2)], axis=1)
    return bones, positions


def project(motion: Motion, view: str = "side") -> tuple[np.ndarray, np.ndarray]:
    """The motion as drawn: bone ends ``[F, B, 2, 2]`` (picture x to the right, y up, file
    units) and the horizontal picture position of the hips ``[F]`` (the GIF's camera follows them).
    A file whose data stand along another axis than Y (Z-up SMPL or game rigs) is drawn upright."""
    from ..body.conventions import upright

    motion = upright(motion)
    take = Take.of(motion)
    bones, positions = _segments(take)
    axis = _horizontal_axis(heading(take), view)
    try:
        hips = take.body.roles.hips
    except MocapError:
        hips = 0
    flat = np.stack([bones @ axis, bones[..., 1]], axis=-1)
    return flat, positions[:, hips] @ axis


def _drawing_scales(motions: Sequence[Motion]) -> list[float]:
    """Per motion, what its units are drawn at so that panels share one real scale (centimetres
    beside a CMU file's units drew that actor a fifth of the other's height): its metres per unit,
    as read from its data (an unknown unit's stands the actor 1.70 m tall); file units for all
    where one cannot be read."""
    from ..body.conventions import read_conventions

    try:
        return [read_conventions(m, Body.of(m.skeleton).joint_map).metres_per_unit for m in motions]
    except MocapError:
        return [1.0] * len(motions)


def _vertical_range(flat: Sequence[np.ndarray]) -> tuple[float, float]:
    """Floor (or lowest point) to the top of every drawn figure."""
    low = min(0.0, min(float(f[..., 1].min()) for f in flat))
    return low, max(float(f[..., 1].max()) for f in flat)


def _line_width(figure_points: float) -> float:
    """Line width (points) for a figure drawn ``figure_points`` tall: thin lines on a small one."""
    return float(np.clip(0.009 * figure_points, 0.6, 2.2))


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
    if view not in VIEWS:
        raise MocapError(f"view must be one of {', '.join(VIEWS)}, got {view!r}")
    titles = list(titles) if titles is not None else [""] * len(motions)
    if len(titles) != len(motions):
        raise MocapError(f"{len(titles)} titles for {len(motions)} motions")
    return titles


def _shade(k: int, n: int) -> float:
    """0.25 .. 1 from the first of ``n`` poses to the last: later poses darker."""
    return 0.25 + 0.75 * (k + 1) / n


def pose_figure(motions: Sequence[Motion], titles: Sequence[str] | None = None, poses: int = 8, view: str = "side"):
    """The matplotlib Figure :func:`render_poses` saves: one panel per motion, each showing
    ``poses`` evenly spaced frames where they happened (a chronophotograph: a walk spreads along
    its path), later poses darker, and a legend saying so."""
    from matplotlib.lines import Line2D
    from matplotlib.transforms import blended_transform_factory

    titles = _check(motions, titles, view)
    frames = [np.linspace(0, m.n_frames - 1, min(poses, m.n_frames)).round().astype(int) for m in motions]
    drawn = [project(m, view)[0][f] * scale for m, f, scale in zip(motions, frames, _drawing_scales(motions))]
    low, top = _vertical_range(drawn)
    margin = MARGIN * (top - low)
    spans = [np.ptp(d[..., 0]) + 2 * margin for d in drawn]
    height_span = top - low + 2 * margin
    aspect = max(spans) / height_span
    width, height = float(np.clip(aspect * 2.6, 2.5, 14.0)), 2.8
    stacked = aspect > 2.5
    plt, fig, axes = _figure(len(motions), width=width, height=height, stacked=stacked)
    # Aspect is equal: the panel's tighter dimension sets the scale, and so the figure's size in points.
    inches_per_unit = min(width / max(spans), height / height_span)
    lw = _line_width((top - low) * inches_per_unit * 72)
    cmap = plt.cm.viridis
    for ax, flat, title in zip(axes, drawn, titles):
        for k, pose in enumerate(flat):
            colour = cmap(1 - _shade(k, len(flat)))
            for a, b in pose:
                ax.plot([a[0], b[0]], [a[1], b[1]], color=colour, lw=lw, solid_capstyle="round")
        ax.axhline(0.0, color="0.7", lw=0.8)
        middle = (flat[..., 0].min() + flat[..., 0].max()) / 2
        ax.set_xlim(middle - max(spans) / 2, middle + max(spans) / 2)  # one scale for every panel
        ax.set_ylim(low - margin, top + margin)
        ax.set_title(title, fontsize=10)
    n = max(len(f) for f in frames)
    handles = [Line2D([], [], color=cmap(1 - _shade(k, n)), lw=2) for k in (0, n - 1)]
    under = blended_transform_factory(fig.transFigure, axes[-1].transAxes)  # centred, just below the last panel
    fig.legend(
        handles,
        ["first frame", "last frame"],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.02),
        bbox_transform=under,
        ncol=2,
        fontsize=8,
        frameon=False,
        title=f"{n} poses evenly spaced in time, later ones darker",
        title_fontsize=8,
    )
    return fig


def render_poses(
    motions: Sequence[Motion],
    path: str | os.PathLike,
    titles: Sequence[str] | None = None,
    poses: int = 8,
    view: str = "side",
) -> None:
    """PNG of :func:`pose_figure`."""
    import matplotlib.pyplot as plt

    _save(pose_figure(motions, titles, poses, view), plt, path)


def gif_timing(fps: Sequence[float], seconds: float, speed: float = 1.0) -> tuple[np.ndarray, np.ndarray, int]:
    """When each GIF frame is taken and how long it shows, for clips at frame rates ``fps`` lasting
    ``seconds`` (the longest), played at ``speed`` x real time: clip times ``[K]`` (s) and delays
    ``[K]`` (ms, whole 10 ms: GIFs count hundredths), and the step in frames of the fastest clip.

    The GIF takes every ``step``-th frame of the fastest clip, the fewest that keeps delays at
    least 20 ms, and rounds the running time, not each delay, to 10 ms: a 30 fps clip plays with
    delays 30, 30, 40 ms..., ending within 20 ms of real time instead of 10% early."""
    rate = max(fps)
    step = math.ceil(MIN_GIF_DELAY * rate * speed - 1e-9)
    period = step / rate  # of clip time per GIF frame
    frames = max(1, math.ceil(seconds / period - 1e-9))
    times = np.arange(frames) * period
    ends = times + period
    ends[-1] = max(seconds, times[-1] + MIN_GIF_DELAY * speed)  # the last frame ends with the clip
    shown = np.floor(np.concatenate([[0.0], ends]) / speed * 100 + 0.5)  # running time, hundredths
    return times, np.diff(shown).astype(int) * 10, step


def render_animation(
    motions: Sequence[Motion],
    path: str | os.PathLike,
    titles: Sequence[str] | None = None,
    view: str = "side",
    speed: float = 1.0,
    progress: bool | None = None,
) -> str:
    """Animated GIF, one panel per motion, the camera following each walker's hips horizontally.
    Motions play on one clock at ``speed`` x real time (each its own frame rate, see
    :func:`gif_timing`); shorter ones hold their last pose. Returns a line saying how it plays.
    ``progress``: a bar of the GIF frames drawn on stderr (:class:`~expressive_mocap._utils.
    progress.Progress`); None: only when stderr is a terminal."""
    # Layout, timing, drawing and writing of one GIF in order: a little over 60 lines, kept whole.
    from PIL import Image

    titles = _check(motions, titles, view)
    if not (np.isfinite(speed) and speed > 0):
        raise MocapError(f"speed must be a positive number, got {speed}")
    seconds = max(m.n_frames * m.frame_time for m in motions)
    times, delays, step = gif_timing([m.fps for m in motions], seconds, speed)
    projected = []
    for motion, scale in zip(motions, _drawing_scales(motions)):
        flat, centre = project(motion, view)
        index = np.minimum(np.floor(times * motion.fps + 1e-6).astype(int), motion.n_frames - 1)
        projected.append(scale * (flat[index] - np.stack([centre[index], np.zeros(len(index))], -1)[:, None, None]))
    low, top = _vertical_range(projected)
    margin = MARGIN * (top - low)
    extent = max(float(np.abs(p[..., 0]).max()) for p in projected) + margin
    width, height = 3.2, 4.0
    plt, fig, axes = _figure(len(motions), width, height)
    lw = _line_width((top - low) * min(width / (2 * extent), height / (top - low + 2 * margin)) * 72)
    lines = []
    for ax, flat, title in zip(axes, projected, titles):
        ax.set_xlim(-extent, extent)
        ax.set_ylim(low - margin, top + margin)
        ax.axhline(0.0, color="0.7", lw=0.8)
        ax.set_title(title, fontsize=10)
        lines.append(
            [ax.plot([], [], color="tab:blue", lw=lw, solid_capstyle="round")[0] for _ in range(flat.shape[1])]
        )
    clock = fig.text(0.02, 0.02, "", fontsize=8, color="0.4")
    fig.tight_layout()
    images = []
    bar = Progress(len(times), "render", "frames", enabled=_progress_wanted(progress))
    for k, t in enumerate(times):
        for flat, panel in zip(projected, lines):
            for (a, b), line in zip(flat[k], panel):
                line.set_data([a[0], b[0]], [a[1], b[1]])
        clock.set_text(f"{t:.1f} s" + (f" (x{speed:g})" if speed != 1 else ""))
        fig.canvas.draw()
        images.append(
            Image.frombuffer(
                "RGBA", fig.canvas.get_width_height(), fig.canvas.buffer_rgba(), "raw", "RGBA", 0, 1
            ).convert("RGB")
        )
        bar.update(1, "drawing" if k + 1 < len(times) else "encoding the GIF")
    plt.close(fig)
    buffer = io.BytesIO()
    images[0].save(buffer, format="GIF", save_all=True, append_images=images[1:], duration=delays.tolist(), loop=0)
    atomic_write(path, buffer.getvalue())
    bar.update(0, f"wrote {os.fspath(path)}")
    bar.close()
    played = delays.sum() / 1000
    rates = " and ".join(sorted({f"{m.fps:.4g}" for m in motions}, key=float))
    taken = "every frame" if step == 1 else f"every {step} frames"
    return (
        f"{len(times)} frames ({taken} of {rates} fps) playing {played:.2f} s for {seconds:.2f} s of motion: "
        f"{seconds / played:.3f} x real time" + (f" (asked {speed:g})" if speed != 1 else "")
    )


def render(
    motions: Sequence[Motion],
    path: str | os.PathLike,
    titles: Sequence[str] | None = None,
    view: View = "side",
    *,
    poses: int = 8,
    speed: float = 1.0,
    progress: bool | None = None,
) -> str | None:
    """Render to ``path``: a GIF animation if it ends in ``.gif`` (:func:`render_animation`, played
    at ``speed`` x real time; returns how it plays; ``progress``: a bar of its frames on stderr,
    None: only on a terminal), otherwise a PNG of ``poses`` poses per motion
    (:func:`render_poses`: one figure, no bar). ``path`` is checked before drawing
    (:func:`expressive_mocap._utils.files.output_target`)."""
    output_target(path)
    if isinstance(poses, bool) or not isinstance(poses, (int, np.integer)) or poses < 1:
        raise ArgumentError(f"argument `poses`: expected a whole number of poses >= 1, got {poses!r}")
    if str(path).lower().endswith(".gif"):
        return render_animation(motions, path, titles, view, speed, progress)
    if str(path).lower().endswith(".png"):
        render_poses(motions, path, titles, int(poses), view)
        return None
    raise MocapError(f"render: the output must end in .png or .gif, got {path}")


def _progress_wanted(progress: bool | None) -> bool:
    """Whether to show a bar: as asked, or (None) when stderr is a terminal."""
    if progress is None:
        return bool(getattr(sys.stderr, "isatty", lambda: False)())
    return bool(progress)


def _save(fig, plt, path: str | os.PathLike) -> None:
    buffer = io.BytesIO()
    fig.tight_layout()
    fig.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    plt.close(fig)
    atomic_write(path, buffer.getvalue())


def plot_contacts(
    contacts: np.ndarray,
    frame_time: float,
    path: str | os.PathLike,
    title: str = "",
    labels: Sequence[str] = ("left foot", "right foot"),
) -> None:
    """A gait diagram PNG: one row per foot (``contacts bool [F, S]``, rows top to bottom in
    ``labels`` order), a bar for each contact, time in seconds along the bottom."""
    import matplotlib

    matplotlib.use("Agg")  # files only, no display needed
    import matplotlib.pyplot as plt

    from ..body.contacts import contact_intervals

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


__all__ = [
    "MARGIN",
    "MIN_GIF_DELAY",
    "VIEWS",
    "View",
    "gif_timing",
    "heading",
    "plot_contacts",
    "pose_figure",
    "project",
    "render",
    "render_animation",
    "render_poses",
]
