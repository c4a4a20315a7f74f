"""Running the batches on this machine: a pipeline of threads (header threads, one kernel
thread, one model thread with --model, the caller writing), results in order, memory bounded."""

from __future__ import annotations

import itertools
import os
import queue
import threading
from collections import deque
from collections.abc import Iterator
from concurrent.futures import CancelledError, Future

from . import work
from .format import MODEL_KINDS
from .model_step import run_model
from .sources import Item


def batched(items: Iterator[Item], batch_bytes: float) -> Iterator[list[Item]]:
    """Batches of about ``batch_bytes`` of BVH text. The first ones are smaller (1/8, 1/4,
    1/2 of it): nothing overlaps the parsing of the first batch, so a small one starts the
    pipeline sooner."""
    batch: list[Item] = []
    size, limit = 0, batch_bytes / 8
    for item in items:
        batch.append(item)
        size += item.size
        if size >= limit:
            yield batch
            batch, size, limit = [], 0, min(2 * limit, batch_bytes)
    if batch:
        yield batch


def local(
    batches, limit, stopped, keep, model, model_float32, canonical: dict | None = None, options=work.PLAIN
) -> Iterator[tuple]:
    """``(batch, outcomes, seconds reading headers, seconds in the kernels)`` of each batch in
    order, on this machine, up to ``limit`` batches (``stopped`` gets an entry if more were left).

    A pipeline of threads: header threads read the next batches' headers (from a zip: decompress
    them) and prepare the kernel's arguments (:func:`.work.prepare`), one kernel thread runs each
    batch's kernel call, whose Rust threads use every core, and the caller writes the batch
    before (and takes the next batches: a tar stream is decompressed there). Headers and writing are
    Python and hold the GIL, the kernels do not: separate threads keep the cores busy with
    kernels while they run. (When each thread did a whole batch, the threads fell into step,
    reading headers at the same time on one core and then running kernels at the same time:
    0.92 s for dataset-2 against 0.80 s.) Two header threads on two cores or more decompress
    two batches of a zip at once. With the body-mechanics model, a model thread runs each
    batch's model (:mod:`.model_step`) while the kernel thread runs the next batch's clips."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    in_flight = 3  # batches read ahead of the one being written: bounds memory
    running: deque = deque()
    header_pool, kernel_pool = Workers(min(2, cores), "headers"), Workers(1, "kernels")
    # The model (NumPy between its kernel calls, one core) in a thread of its own: one batch's
    # model overlaps the next one's clip kernels. (In the kernel thread it held the other cores
    # idle: 2 cores ran a --model run 1.3-1.5x faster than 1.)
    model_pool = Workers(1, "model") if any(k in MODEL_KINDS for k in keep) else None
    # Held during each kernel call. A stopped run waits for the calls under way (they end: their
    # reads never block) so that no thread is in Rust when the interpreter exits (one returning
    # from Rust then aborts the process: "FATAL: exception not rethrown"), but it does not wait
    # for a header thread (pure Python) or for batches not started.
    in_kernels, in_model, stopping = threading.Lock(), threading.Lock(), threading.Event()

    def compute(batch, prepared: Future):
        ready = prepared.result()
        with in_kernels:
            if stopping.is_set():
                raise CancelledError
            ran = work.run_clips(batch, ready, keep, model, options)
        return ran if model_pool is not None else run_model(ran, keep, model, model_float32)

    def compute_model(clips_ran: Future):
        ran = clips_ran.result()
        with in_model:
            if stopping.is_set():
                raise CancelledError
            return run_model(ran, keep, model, model_float32)

    def submit_next() -> None:
        batch = next(batches, None)  # taken here, in order (a tar stream is read here)
        if batch is None:
            return
        prepared = header_pool.submit(work.prepare, batch, keep, model, canonical, options)
        computed = kernel_pool.submit(compute, batch, prepared)
        running.append((batch, computed if model_pool is None else model_pool.submit(compute_model, computed)))

    try:
        for _ in range(in_flight):
            submit_next()
        for count in itertools.count():
            if not running:
                return
            if limit is not None and count >= limit:
                stopped.append(True)
                return
            batch, computed = running.popleft()
            result = computed.result()
            submit_next()
            yield (batch, *result)
    finally:  # done, or stopped by Ctrl-C or an error: the batches read ahead are dropped
        for pool in (header_pool, kernel_pool, model_pool):
            if pool is not None:
                pool.close()
        with in_kernels, in_model:
            stopping.set()


class Workers:
    """Daemon threads taking tasks in order (``submit`` returns a Future), for the pipeline of
    :func:`local`. Not a ThreadPoolExecutor: that one runs all its queued tasks when closed and
    joins its threads at interpreter exit, so a Ctrl-C waited for the batches read ahead (5.5 s
    with a model) or for ever for a blocked read. ``close`` cancels the tasks not started; a
    running one ends on its own and nothing waits for it here."""

    def __init__(self, count: int, name: str):
        self._count = count
        self._tasks: queue.SimpleQueue = queue.SimpleQueue()
        for number in range(count):
            threading.Thread(target=self._work, name=f"preprocess-{name}-{number}", daemon=True).start()

    def submit(self, call, *args) -> Future:
        future: Future = Future()
        self._tasks.put((future, call, args))
        return future

    def _work(self) -> None:
        while (task := self._tasks.get()) is not None:
            future, call, args = task
            if future.set_running_or_notify_cancel():
                try:
                    future.set_result(call(*args))
                except BaseException as error:  # handed to whoever takes the result
                    future.set_exception(error)
            del task, future, call, args  # hold no batch while waiting for the next task

    def close(self) -> None:
        while True:
            try:
                task = self._tasks.get_nowait()
            except queue.Empty:
                break
            if task is not None:
                task[0].cancel()
        for _ in range(self._count):
            self._tasks.put(None)


__all__ = ["Workers", "batched", "local"]
