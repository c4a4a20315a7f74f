"""``preprocess --dask ADDRESS`` where no Dask scheduler answers: something that accepts
connections and never speaks (it hung for ever), or answers junk (a traceback). Each is one
error naming the address within a bounded time, and OUT stays resumable."""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path

import pytest

import expressive_mocap as em
import expressive_mocap.dataset.cluster as cluster_module
from expressive_mocap.dataset import load_dataset, preprocess
from expressive_mocap.errors import DatasetError
from expressive_mocap.procedural import procedural_walk

pytest.importorskip("distributed", reason="the [distributed] extra (Dask) is not installed")


@pytest.fixture
def listener():
    """A TCP listener on loopback: ``start(reply)`` accepts connections and sends ``reply`` (or
    nothing) to each, holding them open; yields the address."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)
    held: list[socket.socket] = []

    def start(reply: bytes) -> str:
        def serve() -> None:
            while True:
                try:
                    connection, _ = server.accept()
                except OSError:
                    return
                held.append(connection)
                if reply:
                    try:
                        connection.sendall(reply)
                    except OSError:
                        pass

        threading.Thread(target=serve, daemon=True).start()
        return f"tcp://127.0.0.1:{server.getsockname()[1]}"

    yield start
    server.close()
    for connection in held:
        connection.close()


@pytest.fixture(scope="module")
def clips(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("clips")
    for k in range(3):
        em.write_bvh(procedural_walk(seconds=1.0 + 0.2 * k), folder / f"walk_{k}.bvh")
    return folder


@pytest.mark.parametrize(
    ("reply", "words"),
    [
        (b"", "no Dask scheduler answered at tcp://127.0.0.1:"),
        (b"HTTP/1.1 200 OK\r\n\r\n" + b"\xff" * 4096, "cannot use a Dask scheduler at tcp://127.0.0.1:"),
    ],
)
def test_an_address_where_no_scheduler_answers_is_one_bounded_error(
    listener, clips, tmp_path, monkeypatch, reply, words
):
    monkeypatch.setattr(cluster_module, "CONNECT_TIMEOUT", 1.0)
    address = listener(reply)
    started = time.monotonic()
    with pytest.raises(DatasetError, match=words) as refused:
        preprocess(clips, tmp_path / "out", cluster=address, progress=False)
    assert time.monotonic() - started < 30
    assert "run the same command again to resume" in str(refused.value) and "\n" not in str(refused.value)
    summary = preprocess(clips, tmp_path / "out", progress=False)  # resumable: here, on this machine
    assert summary.finished and len(load_dataset(tmp_path / "out")) == 3
