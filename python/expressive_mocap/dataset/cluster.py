"""Running the batches on a Dask cluster (``preprocess(cluster=...)``, the ``[distributed]``
extra): a few batches per worker in flight, results taken back in order, so the dataset is the
one a single-machine run writes."""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Iterator

from ..errors import ArgumentError
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
        client = Client(local)

        def close() -> None:
            client.close()
            local.close()

        return client, close
    client = Client(str(cluster))
    closer: Callable[[], None] = client.close
    return client, closer


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


def on_cluster(batches, limit, stopped, client, work) -> Iterator[tuple]:
    """As :func:`~.pipeline.local`, the batches run on a Dask cluster: a few per worker in flight,
    results taken back in order (memory stays bounded, the output is written in order)."""
    window = 2 * max(1, len(client.scheduler_info().get("workers", {})))
    running: deque = deque()
    for count, batch in enumerate(batches):
        if limit is not None and count >= limit:
            stopped.append(True)
            break
        running.append((batch, client.submit(remote_batch, batch, *work, pure=False)))
        if len(running) >= window:
            done, future = running.popleft()
            yield (done, *future.result())
    while running:
        done, future = running.popleft()
        yield (done, *future.result())


__all__ = ["client_for", "on_cluster", "remote_batch"]
