"""The work on one batch of clips, one :class:`Outcome` per clip: :func:`prepare` (Python: the
clips' headers, joint roles, body scales and the kernel's arguments), :func:`run_clips` (one
Rust call per hierarchy, clips in parallel) and :func:`.model_step.run_model` (the
body-mechanics model on the whole batch, the statistics' sums). They run in different threads
on this machine (:mod:`.pipeline`), or together on a cluster's worker (:func:`compute`)."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TypeVar

import numpy as np

from .. import ops
from .._utils import files as inputs
from ..body.body import Body
from ..body.contacts import FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD
from ..bvh import block_error, read_error
from ..errors import BVHError, MocapError, ModelError
from ..motion import Motion, Skeleton
from .derive import Options, resampled
from .format import MODEL_KINDS
from .forms import chunks, derive_group, heading_frames, mirror_values
from .heads import headers_ahead
from .model_step import Ran, run_model
from .sources import Item

PLAIN = Options()  # the stored forms of a run without model-ready options
T = TypeVar("T")
V = TypeVar("V")


@dataclass
class Outcome:
    """What became of one clip of a batch: the ``bytes`` of BVH text read, its ``error`` (text)
    when it failed, else ``frames``, ``fps``, ``frame_time`` and ``values`` (kind -> array as
    stored); ``skeleton`` (joint names, parents) and ``bone_length`` for every clip whose header
    was read. Plain values, so a cluster's worker can send them back."""

    bytes: int = 0
    error: str | None = None
    skeleton: tuple[tuple[str, ...], tuple[int, ...]] | None = None
    bone_length: float = 0.0
    frames: int = 0
    fps: float = 0.0
    frame_time: float = 0.0
    values: dict[str, np.ndarray] = field(default_factory=dict)
    source_skeleton: dict | None = None  # with canonical: the clip's own skeleton and map, if retargeted
    source_fps: float | None = None  # with a resampling fps: the clip's own
    mirrored: dict[str, np.ndarray] | None = None  # with mirror: the mirror image's values
    # (kind, (rows, sums, squares)) in float64 of the clip, then of its mirror image (see .collect)
    sums: list[tuple[str, tuple]] = field(default_factory=list)
    up: tuple | None = None  # the skeleton's up axis as found in its world positions (None: not found)


@dataclass
class Group:
    """The clips of one hierarchy in a batch, ready for one kernel call: their indices in the
    batch, headers (None for a clip retargeted here), the kernel's per-clip arguments (BVH text,
    or arrays for clips retargeted here), the skeleton's parents and gait joints."""

    indices: list[int]
    headers: list
    clips: list  # of ops.ClipInput, or of ops.ClipArrays
    parents: np.ndarray
    gait_joints: list[int]
    skeleton: Skeleton | None = None
    mirrors: list = field(default_factory=list)  # with mirror: the clips' mirror images (ops.ClipArrays)


@dataclass
class Prepared:
    """A batch with its headers read: outcomes so far (errors, skeletons), its groups, seconds taken."""

    outcomes: list[Outcome]
    groups: list[Group]
    seconds: float


def load_model(model):
    """The body-mechanics model of a file, or the shipped one for ``""``."""
    from ..decoupling.body_model import BodyModel

    return BodyModel.load(None if model == "" else model)


def _described(skeleton: Skeleton) -> tuple[tuple, float]:
    """A clip's hierarchy as the dataset compares them (joint names, parents), and its bone length."""
    return (tuple(skeleton.names), tuple(skeleton.parents.tolist())), bone_length(skeleton)


def bone_length(skeleton) -> float:
    """The summed lengths of a skeleton's bones (offsets, End Sites included), in file units:
    what tells a skeleton in metres from the same one in centimetres, whatever its axes."""
    sites = np.array([offset for _, offset in skeleton.end_sites], dtype=np.float64).reshape(-1, 3)
    return float(np.linalg.norm(skeleton.offsets, axis=1).sum() + np.linalg.norm(sites, axis=1).sum())


def by_identity(compute: Callable[[T], V]) -> Callable[[T], V]:
    """``compute`` remembered by the identity of its argument, which is kept alive meanwhile:
    the files that repeat one header share its Skeleton object, so a batch's clips are described
    once per header, not once per clip (2,900 times for dataset-2: 0.08 s holding the GIL)."""
    memo: dict[int, tuple[T, V]] = {}

    def remembered(argument: T) -> V:
        found = memo.get(id(argument))
        if found is None:
            found = memo[id(argument)] = (argument, compute(argument))
        return found[1]

    return remembered


def compute(
    batch: list[Item],
    keep: tuple[str, ...],
    model,
    model_float32: bool,
    canonical: dict | None = None,
    options: Options = PLAIN,
) -> tuple[list[Outcome], float, float]:
    """The work on one batch, one outcome per item, as a cluster's worker does it. Returns the
    outcomes and the seconds spent preparing (headers) and in the kernels."""
    return run_kernels(batch, prepare(batch, keep, model, canonical, options), keep, model, model_float32, options)


def prepare(
    batch: list[Item], keep: tuple[str, ...], model, canonical: dict | None = None, options: Options = PLAIN
) -> Prepared:
    """The Python work before a batch's kernels: the clips' headers, from the files' first bytes
    (:func:`~expressive_mocap.bvh.read_header`; zip members are decompressed here, a tar's
    members come already read), each hierarchy's joint roles and each clip's body scale and
    channel layout. ``canonical`` (a joint map, ``{}`` for none; None: off): clips of any other
    skeleton than the canonical body are read whole and retargeted onto it here
    (:func:`onto_canonical`). ``options`` that resample or mirror have every clip read whole
    here, resampled and mirrored (:func:`decoded`)."""
    start = time.perf_counter()
    outcomes = [Outcome() for _ in batch]
    by_hierarchy: dict[tuple, list] = {}  # (names, parents) -> [(index, header, text for the kernel)]
    known = headers_ahead(batch)
    described = by_identity(_described)
    for k, item in enumerate(batch):
        try:
            header, text = item.header(outcomes[k], known.get(k))
        except BVHError as error:
            outcomes[k].error = str(error)
            continue
        shape, outcomes[k].bone_length = described(header.skeleton)
        outcomes[k].skeleton = shape
        by_hierarchy.setdefault(shape, []).append((k, header, text))
    use_model = any(k in MODEL_KINDS for k in keep)
    needs_roles = use_model or "features" in keep or "contacts" in keep
    if canonical is not None:
        by_hierarchy = onto_canonical(batch, outcomes, by_hierarchy, canonical or None, _signed_joints(keep, use_model))
    mirrors: dict[tuple, list] = {}
    if options.decoded:
        by_hierarchy, mirrors = decoded(batch, outcomes, by_hierarchy, options, canonical)
    groups = []
    for shape, members in by_hierarchy.items():
        if not members:
            continue
        group = _group(members, needs_roles, use_model, model, mirrors.get(shape, []))
        if isinstance(group, MocapError):  # the hierarchy lacks a role, or does not fit the model
            hint = _CANONICAL_HINT if use_model and canonical is None and isinstance(group, ModelError) else ""
            for k, _, _ in members:
                outcomes[k].error = f"{batch[k].source}: {group}{hint}"
            continue
        groups.append(group)
    return Prepared(outcomes, groups, time.perf_counter() - start)


_CANONICAL_HINT = " (--canonical retargets clips of any humanoid skeleton onto the model's body)"


def _signed_joints(keep: tuple[str, ...], use_model: bool) -> list[int] | None:
    """The canonical body's joints whose rotations are used with their sign (None: all): every
    joint's when rotations are stored or a model reads them, else the thighs' for the features."""
    if use_model or "rotations" in keep:
        return None
    if "features" not in keep:
        return []
    from ..body.canonical import canonical_skeleton

    return Body.of(canonical_skeleton()).roles.gait_joints[1:3]  # left and right upper leg


def onto_canonical(
    batch: list[Item],
    outcomes: list[Outcome],
    by_hierarchy: dict,
    user_map: dict | None = None,
    signed: list[int] | None = None,
) -> dict:
    """``by_hierarchy`` with every clip of another skeleton than the canonical body retargeted
    onto it (all of a batch at once: :func:`~expressive_mocap.skeletons.canonical.many_onto_canonical`):
    its frames decoded here, in parallel, and handed on as arrays (under the key ``MOVED``: no
    BVH text to write and parse again), its own skeleton and joint map kept in its outcome for
    the manifest. ``user_map``: role -> joint name, for every skeleton of the archive.
    ``signed``: the joints whose rotations must keep the text's sign (:func:`as_written`)."""
    from ..body.canonical import canonical_shape, canonical_skeleton
    from ..skeletons.canonical import many_onto_canonical

    target, body = canonical_shape(), bone_length(canonical_skeleton())  # every retargeted clip's
    out: dict[tuple, list] = {target: by_hierarchy.pop(target, []), MOVED: []}
    read = _decode_whole(batch, outcomes, [m for members in by_hierarchy.values() for m in members])
    for k, _ in read:  # on the canonical body, or failed: never a skeleton of the dataset's own
        outcomes[k].skeleton = None
    try:
        moved = many_onto_canonical([motion for _, motion in read], user_map)
    except Exception:  # one clip of the batch cannot be retargeted: find which, clip by clip
        moved = [_one_onto_canonical(motion, user_map) for _, motion in read]
    for (k, motion), result in zip(read, as_written(moved, signed)):
        if isinstance(result, Exception):
            outcomes[k].error = f"{batch[k].source}: cannot be retargeted onto the canonical body: {result}"
            continue
        clip, jmap = result
        if not (np.isfinite(clip.rotations).all() and np.isfinite(clip.translations).all()):
            outcomes[k].error = f"{batch[k].source}: retargeting onto the canonical body gave non-finite values"
            continue
        skeleton = motion.skeleton
        outcomes[k].source_skeleton = {
            "joints": skeleton.n_joints,
            "root": skeleton.names[0],
            "fps": motion.fps,
            "map": jmap.as_names(),
        }
        outcomes[k].skeleton = target
        outcomes[k].bone_length = body
        out[MOVED].append((k, None, clip))
    return out


def as_written(moved: list, joints: list[int] | None = None) -> list:
    """The retargeted clips of ``moved`` (``(Motion, map)``, or an error) with the rotations of
    ``joints`` (None: all) as their BVH text would read back: the same rotations, each
    quaternion's sign that of its Euler angles' (features take the thighs' hemisphere from a
    clip's first frame). One kernel call each way for all the clips."""
    done = [m for m in moved if not isinstance(m, MocapError)]
    if not done or joints == []:
        return moved
    skeleton = done[0][0].skeleton
    joints = list(range(skeleton.n_joints)) if joints is None else joints
    orders = skeleton.layout()[1][joints]  # the canonical body's: three rotation channels a joint
    picked = np.concatenate([m.rotations[:, joints] for m, _ in done])
    picked = ops.euler_to_quat(ops.quat_to_euler(picked, orders), orders)
    bounds = np.cumsum([0] + [m.n_frames for m, _ in done])
    for (motion, _), a, b in zip(done, bounds[:-1], bounds[1:]):
        motion.rotations[:, joints] = picked[a:b]  # the retarget's own arrays: changed in place
    return moved


# The key in ``by_hierarchy`` of the clips retargeted onto the canonical body (as Motions).
MOVED = ("retargeted",)


def decoded(batch: list[Item], outcomes: list[Outcome], by_hierarchy: dict, options: Options, canonical) -> tuple:
    """``by_hierarchy`` with every clip read whole (as Motions), resampled to ``options.fps``,
    and, with ``options.mirror``, each hierarchy's mirror images (:func:`~expressive_mocap.
    skeletons.mirror.mirror_many`: all of a hierarchy's clips of the batch at once), as
    ``(by_hierarchy, {key: [Motion]})``. A hierarchy that cannot be mirrored fails its clips."""
    from ..skeletons.mirror import mirror_many

    out: dict[tuple, list] = {}
    mirrors: dict[tuple, list] = {}
    for key, members in by_hierarchy.items():
        texts = [m for m in members if m[1] is not None]
        read = {k: motion for k, motion in _decode_whole(batch, outcomes, texts)}
        read.update({k: motion for k, header, motion in members if header is None})
        motions = []
        for k, _, _ in members:
            if k not in read:
                continue
            motion = read[k]
            if options.fps is not None:
                outcomes[k].source_fps = motion.fps
                try:
                    motion = resampled(motion, options.fps)
                except MocapError as error:  # more frames than a motion may hold
                    outcomes[k].error = f"{batch[k].source}: cannot be resampled: {error}"
                    continue
            motions.append((k, None, motion))
        if options.mirror and motions:
            try:
                mirrors[key] = [
                    image
                    for part in chunks([m for _, _, m in motions], lambda m: m.n_frames)
                    for image in mirror_many(part)
                ]
            except MocapError as error:
                for k, _, _ in motions:
                    outcomes[k].error = f"{batch[k].source}: cannot be mirrored: {error}"
                motions = []
        out[key] = motions
    return out, mirrors


def _decode_whole(batch: list[Item], outcomes: list[Outcome], members: list) -> list[tuple[int, Motion]]:
    """``(index, Motion)`` of the clips ``(index, header, text)`` (text: the bytes, or the path
    to read here), their number blocks decoded together (in parallel with the Rust kernels); a
    clip that cannot be read gets its error in its outcome, as the kernel's pipeline gives it."""
    texts = []
    for k, header, text in members:
        try:
            data = text if isinstance(text, bytes) else inputs.read_input(text)
        except OSError as error:
            outcomes[k].error = str(read_error(batch[k].source, error))
            continue
        outcomes[k].bytes = len(data)
        texts.append((k, header, data))
    decoded = ops.read_motion_blocks([(data, header) for _, header, data in texts])
    out = []
    for (k, header, _), result in zip(texts, decoded):
        if isinstance(result, Exception):
            outcomes[k].error = str(_clip_error(batch[k], header, result))
        else:
            rotations, translations = result
            out.append((k, Motion(header.skeleton, rotations, translations, header.frame_time)))
    return out


def _one_onto_canonical(motion, user_map: dict | None):
    """The clip on the canonical body, or why not: its own failure, whatever it is (a clip must
    never stop the run, and the rerun stopped on it again)."""
    from ..skeletons.canonical import onto_canonical as retarget_onto

    try:
        return retarget_onto(motion, user_map)
    except MocapError as error:
        return error
    except Exception as error:  # noqa: BLE001 - a bug's message, as that clip's failure
        return MocapError(f"{type(error).__name__}: {error}")


def _group(members: list, needs_roles: bool, use_model: bool, model, mirrors: list) -> Group | MocapError:
    """One hierarchy's clips ``(index, header, text)`` (or ``(index, None, Motion)``, a clip
    read whole here) and their mirror images (Motions, or none) as one kernel call's arguments,
    or why not."""
    header, first = members[0][1:]
    skeleton = first.skeleton if header is None else header.skeleton
    try:
        roles = Body.of(skeleton).roles if needs_roles else None
        if use_model:
            model.check_skeleton(skeleton)
    except MocapError as error:
        return error

    @by_identity
    def scale(s) -> tuple[float, float]:  # without features or contacts the body scale is not used
        return (Body.of(s).actor_height, Body.of(s).hips_rest_height) if roles else (1.0, 1.0)

    if header is None:  # each clip's own body scale: clips of one hierarchy differ in their offsets
        clips: list = [
            ops.ClipArrays(m.rotations, m.translations, m.frame_time, *scale(m.skeleton)) for _, _, m in members
        ]
        images = [ops.ClipArrays(m.rotations, m.translations, m.frame_time, *scale(m.skeleton)) for m in mirrors]
    else:
        clips, images = [ops.ClipInput.of(text, h, *scale(h.skeleton)) for _, h, text in members], []
    gait_joints = roles.gait_joints if roles else [0] * 7  # without features or contacts: not used
    parents = np.ascontiguousarray(skeleton.parents, dtype=np.int64)
    indices, headers = [k for k, _, _ in members], [h for _, h, _ in members]
    return Group(indices, headers, clips, parents, gait_joints, skeleton, images)


def run_kernels(
    batch: list[Item], prepared: Prepared, keep: tuple[str, ...], model, model_float32: bool, options: Options = PLAIN
) -> tuple[list[Outcome], float, float]:
    """:func:`run_clips`, then :func:`.model_step.run_model`: the outcomes, the seconds
    :func:`prepare` took and the seconds taken here."""
    return run_model(run_clips(batch, prepared, keep, model, options), keep, model, model_float32)


def run_clips(batch: list[Item], prepared: Prepared, keep: tuple[str, ...], model, options: Options = PLAIN) -> Ran:
    """Everything else of each clip (reading the file, its MOTION block, FK, features, contacts)
    as one task of one kernel call per hierarchy, clips in parallel (``clip_pipeline_many``; the
    NumPy twin composes the other kernels' twins; mirror images ride along in the same call),
    then the stored forms of :mod:`.derive` per hierarchy; what the model and the statistics
    still need (:func:`.model_step.run_model`) with them."""
    start = time.perf_counter()
    outcomes = prepared.outcomes
    use_model = any(k in MODEL_KINDS for k in keep)
    # The model reads the local rotations as quaternions: then another form is derived from them.
    plain = options.plain(keep) and not (use_model and options.rotation_columns)
    requests = ([(0.0, None)] if "features" in keep else []) + ([(None, model.thigh_reference)] if use_model else [])
    kept = []  # (values to update, local rotations, model features, fps) of each clip for the model
    finished = []  # (outcome, values) of each clip and mirror image that succeeded, for the sums
    for group in prepared.groups:
        outputs = ops.PipelineOutputs(
            positions=options.positions_needed(keep) or options.heading(keep),
            rotations=options.rotations_needed(keep) or use_model,
            features=tuple(ops.FeatureRequest(*r) for r in requests),
            contacts="contacts" in keep,
            float32=plain and not use_model,
            rotation_columns=options.rotation_columns if plain else 0,
            velocities=plain and "velocities" in keep,
        )
        gait = ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE)
        if isinstance(group.clips[0], ops.ClipArrays):
            results = ops.arrays_pipeline_many(
                group.clips + group.mirrors, group.parents, group.gait_joints, gait, outputs
            )
        else:
            results = ops.clip_pipeline_many(
                group.clips, group.parents, group.gait_joints, gait, outputs, inputs.MAX_INPUT_BYTES
            )
        done = []  # (values, kernel result, frame time) of each clip and mirror image that succeeded
        owners = []  # the outcome of each
        for number, (k, header, clip, result) in enumerate(zip(group.indices, group.headers, group.clips, results)):
            if _finish_clip(batch[k], outcomes[k], header, clip, result, keep, plain):
                done.append((outcomes[k].values, result, clip.frame_time))
                owners.append(outcomes[k])
                if group.mirrors:
                    image = results[len(group.clips) + number]
                    outcomes[k].mirrored = mirrored = mirror_values(outcomes[k].values, image, keep)
                    done.append((mirrored, image, clip.frame_time))
                    owners.append(outcomes[k])
        frames = heading_frames(group, owners, done, keep, options)
        if not plain and done:
            derive_group(group, done, keep, options, frames)
        if use_model:
            kept += [
                (values, result[1], result[2][-1], 1.0 / frame_time)
                for (values, result, frame_time), f in zip(done, frames)
                if f is not False
            ]
        finished += [(owner, values) for (values, _, _), owner in zip(done, owners) if owner.error is None]
    return Ran(outcomes, kept, finished, prepared.seconds, time.perf_counter() - start)


def _finish_clip(
    item: Item,
    outcome: Outcome,
    header,
    clip: ops.ClipInput | ops.ClipArrays,
    result,
    keep: tuple[str, ...],
    plain: bool = True,
) -> bool:
    """One clip's kernel ``result`` into its outcome: its arrays as stored (but positions,
    rotations and velocities only when ``plain``: else :func:`.forms.derive_group` stores them),
    or its error. True if it succeeded."""
    if isinstance(clip, ops.ClipInput) and isinstance(clip.source, str) and not isinstance(result, OSError):
        # the kernel read the file whole
        outcome.bytes = item.size
    if isinstance(result, Exception):
        outcome.error = str(_clip_error(item, header, result))
        return False
    positions, rotations, features, contacts, velocities = result
    values = {"positions": positions, "rotations": rotations, "velocities": velocities} if plain else {}
    values["contacts"] = contacts
    if "features" in keep:
        values["features"] = features[0]
    outcome.frames, outcome.fps, outcome.frame_time = clip.frames, 1.0 / clip.frame_time, clip.frame_time
    outcome.values = {
        kind: v.astype(np.float32) if v.dtype == np.float64 else v for kind, v in values.items() if kind in keep
    }
    return True


def _clip_error(item: Item, header, error: Exception) -> BVHError:
    """The BVHError of a clip whose number block (ParseError) or file (OSError) could not be read."""
    if isinstance(error, OSError):
        return read_error(item.source, error)
    return block_error(item.source, header, error)


__all__ = [
    "Group",
    "Outcome",
    "Prepared",
    "bone_length",
    "by_identity",
    "compute",
    "load_model",
    "prepare",
    "run_kernels",
]
