"""``render``: stick figures of BVH files, as poses over time (PNG) or played (GIF)."""

from __future__ import annotations

from pathlib import Path

from ..errors import MocapError
from ..viz.render import render_animation, render_poses
from .common import default, positive, read_motion, read_on_model
from .decoupling import BODY_MODEL_FIX, add_model_options, body_model

__all__ = ["add_parsers", "cmd_render"]


def add_render(commands) -> None:
    p = commands.add_parser("render", help="stick figures side by side: poses as PNG or an animated GIF")
    p.add_argument("files", nargs="+", metavar="FILE", help="BVH files, one panel each")
    p.add_argument("-o", "--output", required=True, metavar="OUT.png|OUT.gif", help="picture to write")
    view = default(render_poses, "view")
    p.add_argument(
        "--view",
        choices=["side", "front"],
        default=view,
        help=f"camera, relative to the walker's heading: side (walking to the right) or front (default: {view})",
    )
    poses, speed = default(render_poses, "poses"), default(render_animation, "speed")
    p.add_argument("--poses", type=positive(int), default=poses, help=f"poses per panel in a PNG (default: {poses})")
    p.add_argument(
        "--speed", type=positive(float), default=speed, help=f"GIF playback speed, 1 = real time (default: {speed:g})"
    )
    p.add_argument("--start", type=int, default=0, help="first frame (default: 0)")
    p.add_argument("--end", type=int, help="frame to stop before (default: the end)")
    what = p.add_mutually_exclusive_group()
    what.add_argument("--decoupled", action="store_true", help="one file: original | body mechanics | expressive")
    what.add_argument("--modulated", action="store_true", help="one file: expressiveness at 50%% | 100%% | 150%%")
    add_model_options(p)
    p.set_defaults(run=cmd_render)


def cmd_render(args) -> int:
    from ..viz.render import render

    motions = [read_motion(path, args) for path in args.files]
    titles = [Path(p).stem for p in args.files]
    if args.decoupled or args.modulated:
        from ..decoupling.algebra import decompose

        if len(motions) != 1:
            raise MocapError("--decoupled and --modulated draw one file: give exactly one")
        model = body_model(args)
        # A file of another skeleton is decoupled on the model's body, and drawn on its own.
        motion, back = read_on_model(args.files[0], model, BODY_MODEL_FIX, args)
        parts = decompose(motion, model, args.gain, args.exponent)
        if args.decoupled:
            motions = [motions[0], back(parts.body_motion()), back(parts.expressive_motion())]
            titles = ["original", "body mechanics", "expressive"]
        else:
            motions = [back(parts.recompose(s)) for s in (0.5, 1.0, 1.5)]
            titles = ["50% expressive", "100% (original)", "150% expressive"]
    if args.start or args.end:
        motions = [m[args.start : args.end] for m in motions]
    played = render(motions, args.output, titles=titles, view=args.view, poses=args.poses, speed=args.speed)
    print(f"wrote {args.output}" + (f": {played}" if played else ""))
    return 0


def add_parsers(commands) -> None:
    """The subparser of this module's command."""
    add_render(commands)
