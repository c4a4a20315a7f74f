"""Running the batches on a Dask cluster (``preprocess(cluster=...)``, the ``[distributed]``
extra): a few batches per worker in flight, results taken back in order, so the dataset is the
one a single-machine run writes."""

from __future__ import annotations

import concurrent.futures
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator

from .._utils.tokens import shown
from ..errors import ArgumentError, DatasetError
from .sources import Item
from .work import PLAIN, Outcome, compute, load_model


def client_for(cluster) -> tuple:
    """A Dask client for ``cluster`` (a Client, an address or "local") and how to close what was opened here."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ArgumentError("running on a cluster needs Dask: pip install 'expressive-mocap[distributed]'") from None
    if isinstance(cluster, Client):
        return cluster, lambda: None
    if cluster == "local":
        local = LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
        )
        client = Client(local, direct_to_workers=True)

        def close() -> None:
            client.close()
            local.close()

        return client, close
    client = _connect(Client, str(cluster))
    closer: Callable[[], None] = client.close
    return client, closer


# Seconds to reach a scheduler, and for each call to it: Dask bounds the TCP connection but not the
# handshake, so a listener that accepts and never answers hung a run for ever.
CONNECT_TIMEOUT = 20.0
CALL_TIMEOUT = 60.0


def _connect(client_class, address: str):
    """A client of the scheduler at ``address``, or a DatasetError saying what was tried. In a
    daemon thread with a deadline: an unanswered handshake leaves only that thread waiting."""
    box: dict = {}

    def connect() -> None:
        try:
            # Results fetched from the workers themselves: by default a client outside the cluster
            # has the scheduler relay them, every batch's arrays crossing the network twice (if a
            # worker cannot be reached from here, Dask falls back to the relay for its results).
            box["client"] = client_class(address, timeout=CONNECT_TIMEOUT, direct_to_workers=True)
        except BaseException as error:  # noqa: BLE001 - junk from a listener can raise anything (MemoryError)
            box["error"] = error

    thread = threading.Thread(target=connect, name="dask-connect", daemon=True)
    thread.start()
    thread.join(CONNECT_TIMEOUT + 5.0)
    if thread.is_alive():
        raise DatasetError(
            f"no Dask scheduler answered at {address} within {CONNECT_TIMEOUT + 5.0:.0f} s (something accepts "
            f"connections there but does not speak Dask's protocol); {_RESUME}"
        )
    if "error" in box:
        error = box["error"]
        raise DatasetError(
            f"cannot use a Dask scheduler at {address}: {type(error).__name__}: {shown(str(error))}; {_RESUME}"
        ) from None
    return box["client"]


_MODELS: dict = {}


def remote_batch(
    batch: list[Item], keep, model, model_float32: bool, backend: str, canonical: dict | None = None, options=PLAIN
) -> tuple[list[Outcome], float, float]:
    """What a cluster's worker does with one batch: :func:`~.work.compute`, with the model loaded
    once per worker process and the client's backend."""
    from ..backend import use_backend

    if model is not None and model not in _MODELS:
        _MODELS[model] = load_model(model)
    with use_backend(backend):
        return compute(batch, keep, _MODELS.get(model), model_float32, canonical, options)


# How long a run waits for a cluster with no worker (none started yet, or all of them gone)
# before it stops, its batches written so far kept for the rerun.
WAIT_FOR_WORKERS = 60.0


def on_cluster(batches, limit, stopped, client, work) -> Iterator[tuple]:
    """As :func:`~.pipeline.local`, the batches run on a Dask cluster: a few per worker in flight,
    results taken back in order (memory stays bounded, the output is written in order).

    A batch whose worker dies is run again by the scheduler on another worker. A cluster without
    workers for :data:`WAIT_FOR_WORKERS` seconds, a lost scheduler, or a batch that killed every
    worker it was given, stop the run with a :class:`DatasetError` (the batches written so far
    stay: the same command resumes after them)."""
    _wait_for_workers(client)
    window = 2 * max(1, len(_ask(client, client.nthreads)))
    running: deque = deque()
    for count, batch in enumerate(batches):
        if limit is not None and count >= limit:
            stopped.append(True)
            break
        running.append((batch, client.submit(remote_batch, batch, *work, pure=False)))
        if len(running) >= window:
            done, future = running.popleft()
            yield (done, *_result(client, future, done))
    while running:
        done, future = running.popleft()
        yield (done, *_result(client, future, done))


_RESUME = "the batches written so far are kept: run the same command again to resume"


def _wait_for_workers(client) -> None:
    from distributed import TimeoutError as DaskTimeout

    try:
        client.wait_for_workers(1, timeout=WAIT_FOR_WORKERS)
    except DaskTimeout:
        raise DatasetError(
            f"the Dask scheduler at {client.scheduler.address} has no workers (waited {WAIT_FOR_WORKERS:.0f} s): "
            "start some with `dask worker ADDRESS` on machines that can read SRC"
        ) from None


def _result(client, future, batch: list[Item]) -> tuple:
    """A batch's result, waiting while the cluster has workers; an error that says what happened
    (and that the run resumes) when it cannot come."""
    import asyncio  # here: loaded with Dask, not by every run of preprocess

    from distributed import KilledWorker
    from distributed import TimeoutError as DaskTimeout
    from distributed.comm import CommClosedError

    # Cancelled: the client lost the scheduler; closed: a connection to it or to a worker.
    lost = (concurrent.futures.CancelledError, asyncio.CancelledError, CommClosedError)
    idle_since: float | None = None
    while True:
        try:
            return future.result(timeout=1.0)
        except DaskTimeout:
            pass
        except KilledWorker:
            raise DatasetError(
                f"the batch of clips {batch[0].name} .. {batch[-1].name} killed every Dask worker that ran it "
                f"(out of memory? try a smaller --batch-mb); {_RESUME}"
            ) from None
        except lost as error:
            raise _lost(client, error) from None
        try:
            workers = len(_ask(client, client.nthreads))
        except (*lost, OSError, DatasetError) as error:
            raise _lost(client, error) from None
        if workers:
            idle_since = None
            continue
        idle_since = idle_since or time.monotonic()
        if time.monotonic() - idle_since > WAIT_FOR_WORKERS:
            future.cancel()
            raise DatasetError(
                f"every worker of the Dask cluster at {client.scheduler.address} has gone "
                f"(none for {WAIT_FOR_WORKERS:.0f} s); {_RESUME}"
            )


def _ask(client, call):
    """``call()`` of the scheduler, at most :data:`CALL_TIMEOUT` seconds."""
    try:
        return call(callback_timeout=CALL_TIMEOUT)
    except TimeoutError:  # asyncio's and Dask's are the builtin one
        raise DatasetError(f"no answer from the Dask scheduler for {CALL_TIMEOUT:.0f} s") from None


def _lost(client, error: BaseException) -> DatasetError:
    reason = getattr(error, "reason", None) or str(error).rsplit(": ", 1)[-1] or type(error).__name__
    return DatasetError(f"lost the Dask scheduler at {client.scheduler.address} ({reason}); {_RESUME}")


__all__ = ["client_for", "on_cluster", "remote_batch"]
