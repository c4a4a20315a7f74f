"""Commands on skeletons: ``skeleton`` (what the package reads from a file: joint map and
conventions), ``retarget`` (a motion onto another skeleton) and ``fit`` (joint positions as a
motion on a chosen skeleton)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .._utils.tokens import listed
from ..bvh import read_bvh, write_bvh
from ..errors import MocapError
from .common import PROG, add_body_model_option, positive, read_motion

__all__ = ["add_parsers", "cmd_fit", "cmd_retarget", "cmd_skeleton"]

_AXES_HELP = "an axis: X, Y, Z, with a sign for facing (e.g. -Y)"


def _add_convention_options(p, whose: str = "") -> None:
    p.add_argument("--up", metavar="AXIS", help=f"{whose}up axis, instead of reading it from the data ({_AXES_HELP})")
    p.add_argument("--facing", metavar="AXIS", help=f"{whose}facing direction at rest, instead of reading it")
    p.add_argument("--unit", choices=("m", "cm", "mm", "in", "cmu"), help=f"{whose}length unit, instead of guessing it")


def _map_file(path: str | None) -> dict | None:
    from ..body import read_joint_map

    return read_joint_map(path) if path else None


def add_skeleton(commands) -> None:
    p = commands.add_parser(
        "skeleton",
        help="joint map (role -> joint), up axis, facing, unit, actor height and rest pose of BVH files",
        description="What the package reads from each file: the joint playing each role (by names, the "
        "topology, or --map), the joints with no role, and the conventions, each with how sure the guess is.",
    )
    p.add_argument("files", nargs="+", metavar="FILE", help="BVH files (or SMPL/AMASS .npz files, with --body-model)")
    p.add_argument("--map", metavar="MAP.json|MAP.toml", help="roles the names and topology do not find: role -> joint")
    add_body_model_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object per file instead of text")
    _add_convention_options(p)
    p.set_defaults(run=cmd_skeleton)


def describe(path: str, user_map: dict | None, args) -> dict:
    """What ``skeleton`` reports for one file."""
    from ..body import Body, read_conventions
    from ..skeletons.rig import Rig
    from ..skeletons.transfer import untrusted_twists

    motion = read_motion(path, args)
    body = Body.of(motion.skeleton, user_map)
    jmap = body.joint_map
    conventions = read_conventions(motion, jmap).with_overrides(args.up, args.facing, args.unit)
    untrusted = untrusted_twists(motion, Rig(motion.skeleton, jmap, conventions, 0.0))
    names = motion.skeleton.names
    return {
        "file": str(path),
        "joints": motion.skeleton.n_joints,
        "frames": motion.n_frames,
        "fps": round(motion.fps, 6),
        "map": jmap.as_names(),
        "how": {role: jmap.how.get(role, "") for role in jmap.joints},
        "unmapped": [names[j] for j in jmap.unmapped],
        "up": conventions.up,
        "facing": conventions.facing,
        "unit": conventions.unit,
        "metres_per_unit": conventions.metres_per_unit,
        "actor_height": round(body.actor_height, 6),
        "actor_height_m": round(body.actor_height * conventions.metres_per_unit, 3),
        "stature": round(conventions.height, 6),
        "stature_m": round(conventions.height * conventions.metres_per_unit, 3),
        "rest_pose": conventions.rest_pose,
        "sure": conventions.sure,
        "twists_from_positions": sorted(untrusted),
    }


def cmd_skeleton(args) -> int:
    user_map = _map_file(args.map)
    failures = 0
    for path in args.files:
        try:
            report = describe(path, user_map, args)
        except MocapError as error:
            print(f"{PROG}: error: {error}", file=sys.stderr)
            failures += 1
            continue
        if args.json:
            print(json.dumps(report))
            continue
        sure = report["sure"]
        print(f"{path}: {report['joints']} joints, {report['frames']} frames at {report['fps']:.6g} fps")
        print(
            f"  up {report['up']} (sure {sure['up']:.2f}), facing {report['facing']} ({sure['facing']:.2f}), "
            f"unit {report['unit']} ({sure['unit']:.2f}): stature {report['stature_m']:.2f} m; "
            f"rest pose {report['rest_pose']} ({sure['rest_pose']:.2f})"
        )
        print(
            f"  actor height {report['actor_height']:.4g} units = {report['actor_height_m']:.2f} m "
            "(hips standing + spine to the head joint: the scale of contacts and features)"
        )
        print("  role             joint                      found by")
        for role, joint in report["map"].items():
            shown = ", ".join(joint) if isinstance(joint, list) else joint
            print(f"  {role:<16} {shown:<26} {report['how'].get(role, 'the chain from the hips to the chest')}")
        unmapped = report["unmapped"]
        print(f"  unmapped ({len(unmapped)}): {listed(unmapped) if unmapped else 'none'}")
        if unmapped:
            print(
                "  (no role: retargeting turns them as a counterpart in the same place on the other "
                "skeleton, else holds them at rest with their parent; extra spine segments share the "
                "turn from the hips to the chest)"
            )
        if report["twists_from_positions"]:
            print(
                "  twists read from the positions (the rotations twist these bones arbitrarily): "
                + ", ".join(report["twists_from_positions"])
            )
    return 1 if failures else 0


def add_retarget(commands) -> None:
    p = commands.add_parser(
        "retarget",
        help="move a motion onto another skeleton (TARGET's joints, rest pose, axes and unit)",
        description="Each mapped bone of TARGET points where IN's does, through the two rest poses (T, A, "
        "crouched alike); the hips' path is scaled by the legs' lengths; joints TARGET has and IN's map does not "
        "keep their rest rotation (extra spine joints share the spine's turn); feet stay planted through IN's "
        "contacts unless --no-plant-feet. TARGET's own motion is ignored (its frames only tell its up axis and floor).",
    )
    p.add_argument("file", metavar="IN", help="BVH file to move (or an SMPL/AMASS .npz, with --body-model)")
    add_body_model_option(p)
    p.add_argument("--to", required=True, metavar="TARGET.bvh", help="BVH file giving the skeleton and rest pose")
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write the retargeted motion")
    p.add_argument("--map", metavar="MAP", help="joint map file (JSON or TOML) for IN")
    p.add_argument("--to-map", metavar="MAP", help="joint map file for TARGET")
    p.add_argument(
        "--no-plant-feet", dest="plant_feet", action="store_false", help="leave the feet where the bones put them"
    )
    p.add_argument(
        "--fps", type=positive(float), metavar="N", help="resample to N frames a second (default: IN's frame rate)"
    )
    _add_convention_options(p, "IN's ")
    p.set_defaults(run=cmd_retarget)


def cmd_retarget(args) -> int:
    from ..body import Body, Take, read_conventions
    from ..skeletons.retargeting import retarget_rigs, rigs_for
    from ..skeletons.transfer import matched_chains, without_counterpart

    source_map, target_map = _map_file(args.map), _map_file(args.to_map)
    motion = read_motion(args.file, args)
    target = read_bvh(args.to)
    source, goal = Body.of(motion.skeleton, source_map).joint_map, Body.of(target.skeleton, target_map).joint_map
    conventions = None
    if args.up or args.facing or args.unit:
        conventions = read_conventions(motion, source)
        conventions = conventions.with_overrides(args.up, args.facing, args.unit)
    # As skeletons.retarget does, with the rigs at hand to say what has no counterpart.
    take = Take.of(motion)
    source_rig, goal_rig = rigs_for(take, target, source_map, target_map, conventions)
    out = retarget_rigs(take, source_rig, goal_rig, plant_feet=args.plant_feet)
    out = out if args.fps is None else out.resample(fps=args.fps)
    write_bvh(out, args.output)
    carried = [role for role in goal.joints if role in source.joints]
    held, shared = without_counterpart(source_rig, goal_rig)
    matched = [target.skeleton.names[j] for j, _, _, _ in matched_chains(source_rig, goal_rig)]
    print(
        f"{args.output}: {out.n_frames} frames at {out.fps:.6g} fps on {args.to}'s skeleton "
        f"({target.skeleton.n_joints} joints); {len(carried)} roles carried"
        + ("; feet planted" if args.plant_feet else "")
    )
    if matched:
        print(f"  without a role, turned as their counterparts in {args.file}: {listed(matched)}")
    if held:
        print(f"  no counterpart in {args.file}, held at rest with their parents: {listed(held)}")
    if shared:
        print(f"  spine joints sharing the turn from the hips to the chest: {listed(shared)}")
    return 0


def add_fit(commands) -> None:
    p = commands.add_parser(
        "fit",
        help="joint positions (.npy/.npz of a motion model or pose estimator) as a motion on TARGET's skeleton",
        description="Builds the layout's skeleton from the positions (median bone lengths), reads each frame's "
        "rotations from them (bone directions; twists from the hips' and shoulders' lines, the elbows' and knees' "
        "planes, the feet), then retargets that motion onto TARGET (feet planted unless --no-plant-feet) and "
        "reports how far its mapped joints fall from the positions.",
    )
    p.add_argument(
        "file",
        metavar="POSITIONS",
        help=".npy or .npz ([F, J, 3], [N, J, 3, F], [N, F, J, 3] or [F, J*3]; key: positions, "
        "joints, motion, poses, data, arr_0 or its only array; motion-diffusion-model's results.npy too)",
    )
    p.add_argument(
        "--layout",
        metavar="NAME|LAYOUT.json",
        help="the joints' order: humanml3d, smpl24, h36m17 or a JSON layout (joints, parents, map) "
        "(default: the joints and parents an .npz of `positions` carries)",
    )
    p.add_argument(
        "--to",
        required=True,
        metavar="TARGET.bvh",
        help="BVH file of the target rig: its skeleton and rest pose, and from its frames how the rig twists its "
        "limbs, sits its hips and stands its feet",
    )
    p.add_argument("-o", "--output", required=True, metavar="OUT.bvh", help="where to write the fitted motion")
    p.add_argument("--to-map", metavar="MAP", help="joint map file for TARGET")
    p.add_argument(
        "--sample",
        type=_sample,
        default=0,
        metavar="K|all",
        help="which sample of a batch of N (default 0); all: every one, to OUT_0.bvh ... OUT_{N-1}.bvh",
    )
    p.add_argument(
        "--fps",
        type=positive(float),
        metavar="F",
        help="the positions' frame rate (default: the file's, else the layout's)",
    )
    p.add_argument("--up", choices=("y", "z"), help="the positions' up axis (default: read from the data)")
    p.add_argument(
        "--unit", choices=("m", "cm", "mm", "in", "cmu"), help="the positions' length unit (default: guessed)"
    )
    p.add_argument(
        "--no-plant-feet", dest="plant_feet", action="store_false", help="leave the feet where the bones put them"
    )
    p.set_defaults(run=cmd_fit)


def _sample(text: str) -> int | str:
    """``--sample``: a sample's index, or ``all``."""
    if text == "all":
        return text
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a sample's index or all, got {text!r}") from None


def cmd_fit(args) -> int:
    from ..skeletons.fit import fit_positions
    from ..skeletons.layouts import sample_count

    target = read_bvh(args.to)
    if args.sample == "all":
        output = Path(args.output)
        jobs = [(k, output.with_name(f"{output.stem}_{k}{output.suffix}")) for k in range(sample_count(args.file))]
    else:
        jobs = [(args.sample, Path(args.output))]
    for sample, path in jobs:
        out, report = fit_positions(
            args.file,
            args.layout,
            target,
            fps=args.fps,
            up=args.up,
            unit=args.unit,
            sample=sample,
            plant_feet=args.plant_feet,
            target_map=_map_file(args.to_map),
        )
        write_bvh(out, path)
        _print_fit(path, out, report, args, target.skeleton.n_joints)
    return 0


def _print_fit(path: Path, out, report, args, joints: int) -> None:
    """What ``fit`` says of one written motion: where it went, and how closely it follows."""
    cm = 100.0 * report.metres_per_unit
    print(
        f"{path}: {out.n_frames} frames at {out.fps:.6g} fps on {args.to}'s skeleton "
        f"({joints} joints); {len(report.roles)} roles fitted (positions read {report.up} up)"
        + ("; feet planted" if args.plant_feet else "")
    )
    print(
        f"  fit error: mean {report.mean_all * cm:.2f} cm, worst frame {report.worst_frame * cm:.2f} cm "
        f"(target joints vs the positions scaled by the legs' ratio)"
    )
    worst = sorted(report.mean, key=report.mean.__getitem__, reverse=True)[:3]
    print("  largest: " + ", ".join(f"{report.roles[r]} {report.mean[r] * cm:.2f} cm" for r in worst))
    if report.bones:
        bone = max(report.bones, key=report.bones.__getitem__)
        mean = sum(report.bones.values()) / len(report.bones)
        print(
            f"  bone directions: {mean:.2f} degrees from the positions' on average, {report.bones[bone]:.2f} at most "
            f"({bone}; on another body the distances above are mostly its proportions)"
        )


def add_parsers(commands) -> None:
    add_skeleton(commands)
    add_retarget(commands)
    add_fit(commands)
