"""A preprocessing run (:func:`preprocess`): in ``OUT`` locked and free of other datasets,
start or resume the journal in ``OUT/.partial``, process the batches it has not done (on this
machine or a cluster), append each batch's rows and journal line, then finish the dataset."""

from __future__ import annotations

import json
import os
import time
from collections import Counter
from concurrent.futures import Future
from dataclasses import dataclass, field, replace
from pathlib import Path

from .._utils.files import atomic_write
from .._utils.progress import Progress
from ..backend import get_backend
from ..errors import ArgumentError, DatasetError
from .census import rates_of, take_census
from .cluster import client_for, on_cluster
from .collect import collect
from .derive import Options, RunOptions
from .finish import finish, move_into_place
from .folder import finished_manifest, remove_dataset, remove_partial
from .format import DEFAULT_KEEP, JOURNAL, KINDS, MANIFEST, MODEL_KINDS, PARTIAL, RUN, data_file, verify
from .journal import JournalRecord, append_record, not_done, read_journal
from .lock import FolderLock
from .npy import Kind, append_rows, cut_data_files, flush, kinds_for, raise_failed_flush
from .pipeline import Workers, batched, local
from .sources import Item, Source, open_source
from .stats import as_json, merged, statistics
from .summary import MB, Summary
from .work import Outcome, load_model


def preprocess(
    src: str | os.PathLike,
    out: str | os.PathLike,
    keep: tuple[str, ...] | list[str] | str | None = None,
    model: str | os.PathLike | None = None,
    *,
    batch_mb: float = 32.0,
    max_batches: int | None = None,
    model_float32: bool = False,
    cluster=None,
    overwrite: bool = False,
    progress: bool = True,
    canonical: bool = False,
    joint_map: dict | None = None,
    rotations: str | None = None,
    positions: str | None = None,
    fps: float | None = None,
    mirror: bool = False,
    smpl_model: str | os.PathLike | None = None,
) -> Summary:
    """Preprocess every clip of ``src`` (folder, glob, .zip or tar) into the dataset folder ``out``.

    ``keep``: kinds to store (see :data:`KINDS`; a comma-separated string or a sequence;
    default positions, features, contacts, plus activity with a model). ``model``: a
    body-mechanics model file, or ``""`` for the shipped one (needed for activity, body,
    expressive). Clips are read in batches of about ``batch_mb`` MB of BVH text.
    ``max_batches``: stop after that many batches (the run resumes when called again with the
    same arguments). ``model_float32``: run the network in float32 (see
    :func:`~expressive_mocap.decoupling.algebra.decompose_many`).
    ``cluster``: run the batches on a Dask cluster instead of this process: a
    ``distributed.Client``, a scheduler address, or ``"local"`` (a LocalCluster of 2 worker
    processes on 127.0.0.1); needs the ``[distributed]`` extra. The batches are written in order
    as they come back, so the dataset is the one a single-machine run writes.
    ``overwrite``: redo a folder that already holds a finished dataset.
    ``canonical``: take clips of any humanoid skeleton, each retargeted onto the canonical body
    (:mod:`expressive_mocap.skeletons.canonical`), its own skeleton and joint map recorded in its
    manifest record (``source_skeleton``); without it, one dataset holds one skeleton.
    ``joint_map``: with ``canonical``, role -> joint name for roles the names and topology do not
    find (:func:`~expressive_mocap.body.read_joint_map`), for every skeleton of the archive.

    Model-ready arrays (docs/preprocessing.md, "Model-ready arrays"): ``rotations`` the stored
    form of the rotations (``"quaternion"``, ``"6d"``, ``"matrix"``, ``"axis-angle"``,
    ``"euler:ZXY"``); ``positions`` their frame (``"world"``, ``"root"``, ``"heading"``,
    ``"clip"``); ``fps`` resamples every clip first; ``mirror`` stores each clip's mirror image
    after it (``{name}@mirrored``). ``smpl_model``: an SMPL-family body model file (the user's
    own, see :func:`~expressive_mocap.skeletons.read_smpl`): SMPL/AMASS parameter files
    (``*.npz``; not AMASS's ``shape.npz``) in ``src`` are clips too, each read on it. The kinds
    ``velocities``, ``accelerations``, ``root_velocity`` and ``angular_velocities`` may be kept;
    the manifest records every float kind's mean and std (``manifest["stats"]``).
    Returns a :class:`Summary`.
    """
    started = time.perf_counter()
    out = Path(out)
    kept = _keep(keep, model)
    if any(k in MODEL_KINDS for k in kept) and model is None:
        needed = ", ".join(k for k in kept if k in MODEL_KINDS)
        raise ArgumentError(f"keeping {needed} needs a body-mechanics model (--model)")
    if batch_mb <= 0:
        raise ArgumentError(f"batch_mb must be positive, got {batch_mb}")
    shaping = Options.of(rotations, positions, fps, mirror)
    body_model = load_model(model) if model is not None else None
    # The source in one canonical form (a resumed run may spell it otherwise: relative, through a link).
    source_path = os.path.realpath(src) if Path(src).exists() else os.path.abspath(src)
    smpl_path = os.path.realpath(smpl_model) if smpl_model is not None else None
    options = RunOptions(kept, _model_label(model), bool(model_float32), source_path, get_backend(), bool(canonical),
                         joint_map or None, shaping, smpl_path)  # fmt: skip
    if joint_map and not canonical:
        raise ArgumentError("a joint map is for retargeting clips onto the canonical body: give canonical=True too")
    settings = _Settings(kept, options, body_model, model, model_float32, batch_mb, max_batches, cluster, progress,
                         shaping)  # fmt: skip

    FolderLock(out).refuse_if_held()  # a folder another run is writing: say so, not judge it mid-change
    finished_manifest(out)  # refuse a folder that is not ours before putting a lock file in it
    source = open_source(src, smpl_path)  # a bad SRC (or body model) fails before OUT is touched
    try:
        settings = _with_census(settings, source, bool(canonical))
        out.mkdir(parents=True, exist_ok=True)
        with FolderLock(out):  # held to the end: a second run on OUT fails at once
            manifest = finished_manifest(out)  # again: another run may have changed it meanwhile
            if manifest is not None:
                if not overwrite:
                    return _already_finished(out, manifest, options, started)
                remove_partial(out)
                remove_dataset(out)
            return _run(source, out, settings, started)
    finally:
        source.close()


@dataclass
class _Settings:
    """A run's arguments, checked: the kinds kept, the options recorded, the model loaded and as given."""

    keep: tuple[str, ...]
    options: RunOptions
    body_model: object
    model: str | os.PathLike | None
    model_float32: bool
    batch_mb: float
    max_batches: int | None
    cluster: object
    progress: bool
    shaping: Options
    majority: tuple | None = None  # the hierarchy most clips share (without canonical)


def _with_census(settings: _Settings, source: Source, canonical: bool) -> _Settings:
    """``settings`` after the header scan of the source's clips (:mod:`.census`), before any is
    processed: without ``canonical`` the dataset keeps the skeleton most clips share; with it,
    clips of several frame rates are resampled to the one most share, unless ``fps`` names one."""
    if canonical and settings.shaping.fps is not None:
        return settings
    census = take_census(source)
    if not canonical:
        return replace(settings, majority=census.majority())
    shaping = census.resampling(settings.shaping)
    return replace(settings, shaping=shaping, options=replace(settings.options, shaping=shaping))


@dataclass
class _State:
    """What the dataset in ``.partial`` holds so far: the journal's clips and failures, the names
    taken, the skeleton, the row count and the stored kinds (known once the skeleton is)."""

    partial: Path
    done: Counter
    clips: list[dict] = field(default_factory=list)
    failures: list[dict] = field(default_factory=list)
    taken: set[str] = field(default_factory=set)
    skeleton: dict | None = None
    rows: int = 0
    kinds: list[Kind] | None = None
    batches: int = 0
    sums: dict = field(default_factory=dict)  # the statistics' running sums (see .stats)
    up: list | None = None


def _keep(keep, model) -> tuple[str, ...]:
    if keep is None:
        return DEFAULT_KEEP + (("activity",) if model is not None else ())
    if isinstance(keep, str):
        keep = [k.strip() for k in keep.split(",") if k.strip()]
    unknown = [k for k in keep if k not in KINDS]
    if unknown or not keep:
        raise ArgumentError(
            f"unknown kinds to keep: {', '.join(unknown) or '(none given)'}; choose from {', '.join(KINDS)}"
        )
    return tuple(k for k in KINDS if k in keep)  # a fixed order, whatever the order given


def _model_label(model) -> str | None:
    return None if model is None else "shipped" if model == "" else str(Path(model).resolve())


def _already_finished(out: Path, manifest: dict, options: RunOptions, started: float) -> Summary:
    """A rerun over a finished dataset never rewrites it. After a run killed between putting its
    manifest in place and removing ``.partial``, the same command finishes the cleanup and says
    what the dataset holds; otherwise redoing it needs ``overwrite``."""
    if not (out / PARTIAL).exists():
        raise DatasetError(f"{out} already holds a finished dataset (manifest.json); use --overwrite to redo it")
    if manifest.get("options") != options.record():
        raise DatasetError(
            f"{out} holds a finished dataset made with other options ({manifest.get('options')}); "
            "use --overwrite to redo it with these"
        )
    verify(out, manifest)
    remove_partial(out)
    return _summary_of(out, manifest, started)


def _summary_of(out: Path, manifest: dict, started: float) -> Summary:
    """The summary of a dataset an earlier run finished."""
    done = len(manifest["clips"]) + len(manifest["failures"])
    return Summary(str(out), clips_ok=len(manifest["clips"]), clips_failed=len(manifest["failures"]),
                   clips_resumed=done, failures=manifest["failures"], finished=True,
                   seconds=time.perf_counter() - started, rates=dict(rates_of(manifest["clips"])),
                   clips_mirrored=sum("mirror_of" in clip for clip in manifest["clips"]),
                   skeleton=manifest["skeleton"])  # fmt: skip


def _resume(partial: Path, options: RunOptions, keep: tuple[str, ...], width: int) -> _State:
    """The state of the run in ``partial``: a new one (its options recorded), or the interrupted
    one of the same options, its data files cut back to its last journaled batch."""
    run_file = partial / RUN
    if run_file.exists():
        try:
            previous = json.loads(run_file.read_bytes())
        except (ValueError, RecursionError) as error:
            raise DatasetError(
                f"{run_file}: not a readable record of an interrupted run ({error}); delete {partial}"
            ) from None
        then = previous.get("options") if isinstance(previous, dict) else None
        if then != options.record():
            raise DatasetError(
                f"{partial} holds an interrupted run with other options ({then}); "
                f"rerun with those, or delete {partial} to start again"
            )
    else:
        atomic_write(run_file, json.dumps({"options": options.record()}).encode())
    entries = read_journal(partial / JOURNAL)
    state = _State(partial, Counter(name for e in entries for name in e.items), batches=len(entries))
    state.clips = [c for e in entries for c in e.clips]
    state.failures = [f for e in entries for f in e.failures]
    state.taken = {c["name"] for c in state.clips} | {
        f["name"] for f in state.failures
    }  # a second clip of a name fails
    state.skeleton = next((e.skeleton for e in entries if e.skeleton), None)
    state.rows = entries[-1].rows if entries else 0
    state.sums = next((e.sums for e in reversed(entries) if e.sums is not None), {})
    state.up = next((e.up for e in entries if e.up), None)
    if state.skeleton:
        state.kinds = kinds_for(keep, len(state.skeleton["names"]), width)
        cut_data_files(partial, state.kinds, state.rows)
    return state


def _run(source: Source, out: Path, settings: _Settings, started: float) -> Summary:
    """The run itself, in ``out`` locked and free of other datasets: start or resume the journal
    in ``out/.partial``, process what it has not done, then move the finished files into place."""
    partial = out / PARTIAL
    partial.mkdir(exist_ok=True)
    if (partial / MANIFEST).exists():  # interrupted while moving the finished files into place
        return _summary_of(out, move_into_place(out), started)
    state = _resume(partial, settings.options, settings.keep, settings.shaping.width)
    summary = Summary(str(out), clips_resumed=sum(state.done.values()))
    client, close_client = client_for(settings.cluster) if settings.cluster is not None else (None, lambda: None)
    # Flushes each batch's rows to disk in the background. A daemon worker, never joined: a
    # ThreadPoolExecutor's is joined at exit, and after a Ctrl-C that landed while the main thread
    # held a flush's Future lock, that join waited for ever.
    syncer = Workers(1, "flush")
    try:
        todo, total_bytes, total_files = _todo(source, state.done)
        bar = Progress(total_bytes, "preprocess", "B", enabled=settings.progress)
        files = summary.clips_resumed  # BVH files done, mirror images not counted: the unit of total_files
        stopped: list[bool] = []
        flushes: list[Future] = []
        # Clips decoded into arrays in Python (to resample or mirror them) take ~4x the memory of
        # the Rust pipeline's: batches of half the size (16 MB of text by default) keep the peak
        # near the plain run's (dataset-2 with --mirror: 340 MB, against 820 MB at 64 MB, as fast).
        batches = batched(todo, settings.batch_mb * MB / (2 if settings.shaping.decoded else 1))
        if client is None:
            results = local(batches, settings.max_batches, stopped, settings.keep, settings.body_model,
                            settings.model_float32, settings.options.canonical_map, settings.shaping)  # fmt: skip
        else:
            work = (settings.keep, settings.model, settings.model_float32, get_backend(),
                    settings.options.canonical_map, settings.shaping)  # fmt: skip
            results = on_cluster(batches, settings.max_batches, stopped, client, work)
        for batch, outcomes, headers_s, kernels_s in results:
            record, nbytes, write_s = _write_batch(state, batch, outcomes, settings, syncer, flushes)
            del outcomes  # hold no batch's arrays while the next one is taken
            _count(summary, record, nbytes, headers_s, kernels_s, write_s)
            files += len(batch)
            frames = sum(c["frames"] for c in state.clips)
            bar.update(nbytes, f"{files}{f'/{total_files}' if total_files else ''} files, {frames:,} frames")
        if not stopped:
            t0 = time.perf_counter()
            raise_failed_flush(flushes, wait=True)
            extra = {"up": [0.0, 1.0, 0.0] if settings.shaping.positions != "world" else state.up,
                     "rotations_up": state.up, "stats": statistics(state.sums)}  # fmt: skip
            finish(out, state.kinds or [], state.clips, state.failures, state.skeleton, state.rows, settings.options,
                   extra)  # fmt: skip
            summary.write_s += time.perf_counter() - t0
            summary.finished = True
        bar.close()
    finally:
        syncer.close()
        close_client()
    summary.clips_ok, summary.clips_failed = len(state.clips), len(state.failures)
    summary.clips_mirrored = sum("mirror_of" in clip for clip in state.clips)
    summary.failures = state.failures
    summary.rates, summary.skeleton = dict(rates_of(state.clips)), state.skeleton
    summary.seconds = time.perf_counter() - started
    return summary


def _todo(source: Source, done: Counter) -> tuple:
    """The items left to do, their listed bytes and the source's file count (None for a tar stream)."""
    if source.items is None:
        return not_done(source, done), None, None
    left = list(not_done(source.items, done))
    return iter(left), sum(i.size for i in left), len(source.items)


def _write_batch(
    state: _State, batch: list[Item], outcomes: list[Outcome], settings: _Settings, syncer: Workers, flushes: list
) -> tuple[JournalRecord, int, float]:
    """One batch's rows appended to the data files (synced in the background), then its journal
    line (with the statistics' running sums). Returns its record, the bytes of BVH read and the
    seconds taken."""
    partial, keep = state.partial, settings.keep
    record = JournalRecord(state.batches, [item.name for item in batch])
    nbytes = sum(outcome.bytes for outcome in outcomes)  # bytes read, not sizes declared
    start = time.perf_counter()
    collected = collect(batch, outcomes, state.skeleton, keep, record, state.rows, state.taken, settings.majority)
    state.rows, state.skeleton = collected.rows, collected.skeleton
    if collected.sums:
        state.sums = as_json(merged(state.sums, collected.sums))
    record.sums = state.sums
    if state.up is None and collected.up is not None:
        state.up = record.up = collected.up
    if record.skeleton is not None:  # the first clip parsed: now the row shapes are known
        state.kinds = kinds_for(keep, len(record.skeleton["names"]), settings.shaping.width)
        cut_data_files(partial, state.kinds, 0)
    for kind in state.kinds or ():
        if record.clips:
            append_rows(partial / data_file(kind.name), collected.arrays[kind.name], kind.dtype)
    if record.clips:
        flushes.append(syncer.submit(flush, [partial / data_file(kind.name) for kind in state.kinds or ()]))
    raise_failed_flush(flushes)  # before the journal vouches for rows the disk did not take
    record.rows = state.rows
    append_record(partial / JOURNAL, record)
    state.clips += record.clips
    state.failures += record.failures
    state.batches += 1
    return record, nbytes, time.perf_counter() - start


def _count(
    summary: Summary, record: JournalRecord, nbytes: int, headers_s: float, kernels_s: float, write_s: float
) -> None:
    """A batch written, into the run's summary."""
    summary.headers_s += headers_s
    summary.kernels_s += kernels_s
    summary.write_s += write_s
    summary.frames += sum(c["frames"] for c in record.clips)
    summary.bytes_read += nbytes
    summary.batches += 1
    summary.clips_ok += len(record.clips)
    summary.clips_failed += len(record.failures)
    summary.failures += record.failures


__all__ = ["preprocess"]
