"""The ``demo`` command: a procedural walk and a waving one (no download), written, read back,
measured, decoupled and drawn."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from .. import __version__, backend
from ..bvh import read_bvh, write_bvh
from ..motion import Motion
from ..procedural import walk_and_wave
from .common import DEMO_FILES, default, positive
from .info import cmd_info

__all__ = ["DEMO_FILES", "add_parsers", "cmd_demo"]


def add_demo(commands) -> None:
    p = commands.add_parser(
        "demo", help="generate a procedural walk and a waving one (no download), write, read and draw them"
    )
    p.add_argument(
        "-o",
        "--output",
        default="expressive-mocap-demo",
        metavar="DIR",
        help="folder for the outputs (default: ./expressive-mocap-demo)",
    )
    speed, seconds, side = (default(walk_and_wave, name) for name in ("speed", "seconds", "side"))
    p.add_argument("--speed", type=positive(float), default=speed, help=f"walking speed in m/s (default: {speed:g})")
    p.add_argument(
        "--seconds", type=positive(float), default=seconds, help=f"length of the walk (default: {seconds:g})"
    )
    p.add_argument(
        "--wave", choices=["left", "right"], default=side, help=f"arm that waves in walk_wave.bvh (default: {side})"
    )
    p.set_defaults(run=cmd_demo)


def cmd_demo(args) -> int:
    from ..body.contacts import cadence, foot_contacts, footstrikes
    from ..body.take import Take
    from ..procedural import walk_and_wave
    from ..viz.render import render

    out = Path(args.output)
    out.mkdir(parents=True, exist_ok=True)
    print(f"expressive-mocap {__version__}, kernels: {backend.get_backend()}")
    pair = walk_and_wave(seconds=args.seconds, speed=args.speed, side=args.wave)
    bvh_path, wave_path = out / "walk.bvh", out / "walk_wave.bvh"
    write_bvh(pair.walk, bvh_path)
    write_bvh(pair.waving, wave_path)
    again, waving = read_bvh(bvh_path), read_bvh(wave_path)
    take = Take.of(again)
    drift = float(np.abs(take.positions - pair.walk.positions()).max())
    skeleton = "the Bandai-Namco dataset-2 skeleton"
    print(f"procedural walk at {args.speed} m/s on {skeleton}: {again.n_frames} frames -> {bvh_path}")
    cmd_info(argparse.Namespace(files=[str(bvh_path)]))
    roles, height = take.body.roles, take.body.actor_height
    print(f"  actor height {height:.4g} cm (hips rest height + spine-to-head chain: the rest pose is not upright)")
    print(f"  read back: largest joint position difference {drift:.2e} cm")
    hips = take.positions[:, roles.hips]
    print(
        f"  hips travelled {np.linalg.norm(hips[-1, [0, 2]] - hips[0, [0, 2]]) / 100:.2f} m in {again.duration:.2f} s"
    )
    contacts = foot_contacts(take)
    strikes = footstrikes(contacts)
    left = int(np.count_nonzero(strikes[:, 1] == 0))
    steps = f"{len(strikes)} ({left} left, {len(strikes) - left} right)"
    print(f"  footsteps: {steps}, cadence {cadence(contacts, again.frame_time):.2f} steps/s")
    joints = range(again.skeleton.n_joints)
    changed = [
        again.skeleton.names[j] for j in joints if not np.array_equal(again.rotations[:, j], waving.rotations[:, j])
    ]
    print(f"the same walk waving the {args.wave} arm -> {wave_path} (joints that differ: {', '.join(changed)})")
    titles = ["procedural walk", f"waving the {args.wave} arm"]
    render([again, waving], out / "walk.png", titles=titles)
    seconds = int(again.fps * 1.5)
    render([again[:seconds], waving[:seconds]], out / "walk.gif", titles=titles, view="front")
    print(f"pictures: {out / 'walk.png'}, {out / 'walk.gif'}")
    _demo_decoupling(waving, changed, out)
    return 0


def _demo_decoupling(waving: Motion, arm: list[str], out: Path) -> None:
    """Decouple the waving walk with the shipped model, modulate it, draw both."""
    from ..decoupling.algebra import decompose
    from ..decoupling.body_model import BodyModel
    from ..viz.render import render

    parts = decompose(waving, BodyModel.load())
    names = waving.skeleton.names
    on_arm = [names.index(n) for n in arm]
    elsewhere = [j for j in range(2, len(names)) if j not in on_arm]
    print("decoupled with the shipped body-mechanics model (trained on Bandai-Namco neutral locomotion):")
    print(
        f"  mean activity on the waving arm ({', '.join(arm)}): {parts.activity[:, on_arm].mean():.2f}; "
        f"on the other 17 joints: {parts.activity[:, elsewhere].mean():.3f}"
    )
    write_bvh(parts.body_motion(), out / "walk_wave_body.bvh")
    write_bvh(parts.expressive_motion(), out / "walk_wave_expressive.bvh")
    for scale in (0.5, 1.5):
        write_bvh(parts.recompose(scale), out / f"walk_wave_x{scale:g}.bvh")
    print(f"  wrote walk_wave_body.bvh, walk_wave_expressive.bvh, walk_wave_x0.5.bvh, walk_wave_x1.5.bvh in {out}")
    clip = slice(0, int(waving.fps * 1.5))
    parted = ["original", "body mechanics", "expressive"]
    modulated = ["50% expressive", "100% (original)", "150% expressive"]
    render(
        [waving, parts.body_motion(), parts.expressive_motion()], out / "decouple.png", parted, view="front", poses=4
    )
    render([parts.recompose(s) for s in (0.5, 1.0, 1.5)], out / "modulate.png", modulated, view="front", poses=4)
    render(
        [waving[clip], parts.body_motion()[clip], parts.expressive_motion()[clip]],
        out / "decouple.gif",
        parted,
        view="front",
    )
    print(f"pictures: {out / 'decouple.png'}, {out / 'modulate.png'}, {out / 'decouple.gif'}")


def add_parsers(commands) -> None:
    """The subparsers of this module's commands, in the order ``--help`` lists them."""
    add_demo(commands)
