"""A scheduler address with a port outside 1–65535 is refused by name, before any socket."""

from __future__ import annotations

import contextlib
import socket
import threading
from pathlib import Path

import pytest

import pfaff

EXAMPLE = Path(__file__).parents[2] / "examples" / "pendulum.toml"


@pytest.mark.parametrize("port", [0, 65536, 99999999])
def test_out_of_range_port(port: int) -> None:
    with pytest.raises(pfaff.OptionError, match=f"the port {port} of .* is not 1-65535"):
        pfaff.sweep(EXAMPLE, {"g": [9.0, 10.0]}, samples=3, scheduler=f"tcp://127.0.0.1:{port}")


def _server(answer: bytes | None) -> tuple[socket.socket, int]:
    """A local TCP server that accepts every connection and sends ``answer`` (None: nothing)."""
    srv = socket.socket()
    srv.bind(("127.0.0.1", 0))
    srv.listen(8)
    conns: list[socket.socket] = []

    def serve() -> None:
        while True:
            try:
                c, _ = srv.accept()
            except OSError:  # closed by the test
                return
            conns.append(c)
            if answer is not None:
                with contextlib.suppress(OSError):
                    c.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    return srv, srv.getsockname()[1]


@pytest.mark.parametrize(
    "answer",
    [None, b"\xff" * 64 + b"HTTP/1.1 200 OK\r\n\r\n" * 8],
    ids=["silent", "garbage"],
)
@pytest.mark.slow  # (over a second: the full suite runs it)
def test_a_silent_or_hostile_scheduler_is_refused_within_the_timeout(answer, monkeypatch) -> None:
    from pfaff.sweep import driver

    monkeypatch.setattr(driver, "CONNECT_SECONDS", 0.5)
    srv, port = _server(answer)
    try:
        with pytest.raises(pfaff.OptionError, match=f"127.0.0.1:{port}.*(Dask scheduler|answer)"):
            pfaff.sweep(EXAMPLE, {"g": [9.0, 10.0]}, samples=3, scheduler=f"tcp://127.0.0.1:{port}")
    finally:
        srv.close()
