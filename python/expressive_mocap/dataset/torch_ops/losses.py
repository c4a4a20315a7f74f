"""Small loss terms on windows of positions ``[..., T, J, 3]`` (T frames, J joints), in PyTorch,
read against what a dataset stores: its ``velocities`` and its ``contacts``.

The stored velocities are ``np.gradient``'s within each clip (units per second): central
differences ``(p[t + 1] - p[t - 1]) / (2 dt)``, one-sided at a clip's first and last frame.
:func:`finite_velocities` computes the same within a window, and :func:`velocity_loss` compares
the frames where a window's central differences are the stored ones: every frame but its first
and last (whose stored values use frames outside the window). They hold for positions stored in
the ``world``, ``root`` or ``clip`` frame (and for windows re-expressed in their own frame);
with ``--positions heading`` each frame's velocity is the world's turned into that frame's own
heading, not a difference of the stored positions.
"""

from __future__ import annotations

import torch

from ...errors import ArgumentError


def _positions(name: str, x) -> torch.Tensor:
    if not isinstance(x, torch.Tensor) or not x.is_floating_point():
        raise ArgumentError(f"argument `{name}`: expected a floating-point torch.Tensor, got {type(x).__name__}")
    if x.dim() < 3 or x.shape[-1] != 3:
        raise ArgumentError(f"argument `{name}`: expected shape [..., T, J, 3], got {list(x.shape)}")
    return x


def _rate(fps, like: torch.Tensor, lead: int) -> torch.Tensor:
    """Frames per second as a tensor broadcasting over ``[..., T, J, 3]`` (``lead`` leading axes):
    a number, or one a window ``[...]``."""
    rate = torch.as_tensor(fps, dtype=like.dtype, device=like.device)
    if rate.dim() > lead or not bool((rate > 0).all()):
        raise ArgumentError(
            f"argument `fps`: expected a positive number or one a window (shape of the leading axes, "
            f"{list(like.shape[:lead])}), got {fps!r}"
        )
    return rate.reshape(*rate.shape, 1, 1, 1)


def _valid(valid, frames: int, lead_shape: tuple[int, ...], device) -> torch.Tensor | None:
    """Frame flags ``[..., T]`` from ``valid`` (each window's count of its own frames), or None."""
    if valid is None:
        return None
    counts = torch.as_tensor(valid, device=device)
    if counts.dim() > len(lead_shape):
        raise ArgumentError(
            f"argument `valid`: expected one count a window {list(lead_shape)}, got {list(counts.shape)}"
        )
    return torch.arange(frames, device=device) < counts[..., None]


def finite_velocities(positions: torch.Tensor, fps) -> torch.Tensor:
    """Velocities ``[..., T, J, 3]`` of positions ``[..., T, J, 3]`` at ``fps`` frames a second,
    as the dataset's are made (``np.gradient``): central differences, one-sided at the first and
    last frame (zero for a single frame)."""
    _positions("positions", positions)
    rate = _rate(fps, positions, positions.dim() - 3)
    frames = positions.shape[-3]
    if frames < 2:
        return torch.zeros_like(positions)
    first = positions[..., 1:2, :, :] - positions[..., 0:1, :, :]
    last = positions[..., -1:, :, :] - positions[..., -2:-1, :, :]
    inside = (positions[..., 2:, :, :] - positions[..., :-2, :, :]) / 2
    return torch.cat([first, inside, last], dim=-3) * rate


def velocity_loss(positions: torch.Tensor, velocities: torch.Tensor, fps, valid=None) -> torch.Tensor:
    """Mean squared difference (units^2/s^2, summed over x, y, z, averaged over joints and frames)
    between the central differences of ``positions`` and the stored ``velocities`` (both
    ``[..., T, J, 3]``) over the frames ``1 .. T-2`` of each window, whose stored values are
    central differences of the same frames. ``fps``: the dataset's frames per second (a number,
    or one a window); ``valid``: each window's count of its own frames (a batch's ``valid``: frames
    past it are padding and left out). Zero when no frame counts."""
    _positions("positions", positions)
    _positions("velocities", velocities)
    if velocities.shape != positions.shape:
        raise ArgumentError(
            f"argument `velocities`: expected the positions' shape {list(positions.shape)}, "
            f"got {list(velocities.shape)}"
        )
    frames = positions.shape[-3]
    if frames < 3:
        raise ArgumentError(f"argument `positions`: a window of at least 3 frames, got {frames}")
    rate = _rate(fps, positions, positions.dim() - 3)
    central = (positions[..., 2:, :, :] - positions[..., :-2, :, :]) * (rate / 2)
    error = (central - velocities[..., 1:-1, :, :]).square().sum(-1).mean(-1)  # [..., T - 2]
    flags = _valid(valid, frames, tuple(positions.shape[:-3]), positions.device)
    if flags is None:
        return error.mean()
    mask = flags[..., 2:].to(error.dtype).expand_as(error)  # the frame after each one is the window's own
    return (error * mask).sum() / mask.sum().clamp(min=1)


def foot_contact_loss(positions: torch.Tensor, contacts, feet, fps, valid=None) -> torch.Tensor:
    """Mean squared speed (units^2/s^2) of the foot joints between consecutive frames where the
    stored ``contacts [..., T, 2]`` (left, right; bool or 0/1) say that foot is down in both:
    a planted foot should not move. ``positions [..., T, J, 3]``; ``feet [2, K]``: each side's
    joints (:attr:`SkeletonGraph.feet`: ankle and toe, the joints the contacts are read from);
    ``fps`` and ``valid`` as for :func:`velocity_loss`. Zero when no foot is down."""
    _positions("positions", positions)
    feet = torch.as_tensor(feet, device=positions.device)
    if feet.dim() != 2 or feet.shape[0] != 2 or feet.dtype.is_floating_point:
        raise ArgumentError(f"argument `feet`: expected joint indices [2, K] (left, right), got {list(feet.shape)}")
    contacts = torch.as_tensor(contacts, device=positions.device)
    frames = positions.shape[-3]
    if tuple(contacts.shape) != tuple(positions.shape[:-2]) + (2,):
        raise ArgumentError(
            f"argument `contacts`: expected [..., T, 2] = {list(positions.shape[:-2]) + [2]}, "
            f"got {list(contacts.shape)}"
        )
    rate = _rate(fps, positions, positions.dim() - 3)
    joints = positions[..., feet.reshape(-1), :]  # [..., T, 2K, 3]
    speed2 = ((joints[..., 1:, :, :] - joints[..., :-1, :, :]) * rate).square().sum(-1)  # [..., T - 1, 2K]
    speed2 = speed2.reshape(*speed2.shape[:-1], 2, feet.shape[1]).mean(-1)  # [..., T - 1, 2]
    down = contacts.to(torch.bool)
    mask = down[..., 1:, :] & down[..., :-1, :]
    flags = _valid(valid, frames, tuple(positions.shape[:-3]), positions.device)
    if flags is not None:
        mask = mask & flags[..., 1:, None]
    weight = mask.to(speed2.dtype)
    return (speed2 * weight).sum() / weight.sum().clamp(min=1)


__all__ = ["finite_velocities", "foot_contact_loss", "velocity_loss"]
