"""``--ray``: ``local`` always starts its own instance; an address that is not a Ray head fails fast."""

from __future__ import annotations

import os
import socket
import threading
import time

import pytest

from probecommit.runner import study
from probecommit.runner.study import check_reachable, ray_init_kwargs, ray_session


def _listener(reply: bytes | None):
    """A local port that accepts connections and then answers ``reply`` (None: says nothing)."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(8)
    conns = []

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            conns.append(conn)
            if reply is not None:
                conn.recv(64)
                conn.sendall(reply)

    threading.Thread(target=serve, daemon=True).start()
    return server, conns


@pytest.mark.parametrize("reply", [None, b"HTTP/1.1 400 Bad Request\r\n\r\n", b""], ids=["silent", "http", "closes"])
def test_an_address_that_accepts_but_is_not_ray_fails_within_the_timeout_in_one_line(reply):
    server, conns = _listener(reply)
    address = f"127.0.0.1:{server.getsockname()[1]}"
    if reply == b"":
        reply = None
    t0 = time.perf_counter()
    try:
        with pytest.raises(RuntimeError) as err:
            check_reachable(address, timeout_s=0.5)
    finally:
        server.close()
        for conn in conns:
            conn.close()
    assert time.perf_counter() - t0 < 3
    message = str(err.value)
    assert address in message and "\n" not in message and "Ray head" in message


def test_a_grpc_server_answer_passes_the_probe():
    settings = b"\x00\x00\x00\x04\x00\x00\x00\x00\x00"  # an empty SETTINGS frame, as a gRPC server sends first
    server, conns = _listener(settings)
    try:
        check_reachable(f"127.0.0.1:{server.getsockname()[1]}", timeout_s=2)
    finally:
        server.close()
        for conn in conns:
            conn.close()


def test_local_always_starts_its_own_instance_without_the_recorded_address(monkeypatch):
    """``address="local"`` (never a cluster another process recorded) and no RAY_ADDRESS while it starts."""
    assert ray_init_kwargs("local", 2)["address"] == "local"
    seen = {}

    class FakeRay:
        def is_initialized(self):
            return False

        def init(self, **kwargs):
            seen.update(kwargs, env=os.environ.get("RAY_ADDRESS"))

        def shutdown(self):
            seen["shutdown"] = True

    monkeypatch.setattr("probecommit.engines.require", lambda name: FakeRay())
    monkeypatch.setenv("RAY_ADDRESS", "10.0.0.1:6379")
    with ray_session("local", 2, {}):
        pass
    assert seen["address"] == "local" and seen["num_cpus"] == 2 and seen["env"] is None and seen["shutdown"]
    assert os.environ["RAY_ADDRESS"] == "10.0.0.1:6379"  # restored for the rest of the process


def test_a_ray_start_that_hangs_is_given_up_with_one_line(monkeypatch):
    class HangingRay:
        def is_initialized(self):
            return False

        def init(self, **kwargs):
            time.sleep(30)

        def shutdown(self):
            pass

    monkeypatch.setattr("probecommit.engines.require", lambda name: HangingRay())
    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match=r"could not start a local Ray instance within 0.3 s"):
        with ray_session("local", 1, {}, timeout_s=0.3):
            pass
    assert time.perf_counter() - t0 < 3
    assert study.RAY_START_TIMEOUT_S > 0
