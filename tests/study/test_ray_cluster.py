"""A Ray cluster's address (issue 25, item 2): parsed, then reached within seconds, before any planning; an address
where no cluster answers is a one-line ClusterConnectionError naming it, never Ray's endless retries. No Ray cluster
runs here: the servers are sockets of this test."""

import socket
import threading
import time
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from regrasp.core.exceptions import ClusterConnectionError, InvalidParameterError, RegraspError
from regrasp.study.ray_cluster import CLIENT_PORT, RayAddress, check_ray_address, parse_ray_address

SCENARIO = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "paper_trajectory_2_three_fingers.toml"


def unused_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Server:
    """A local TCP server that answers each connection with ``reply`` (None: says nothing, keeps it open; empty:
    closes it)."""

    def __init__(self, reply: bytes | None):
        self.sock = socket.socket()
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(8)
        self.port = self.sock.getsockname()[1]
        self.reply, self.held = reply, []
        threading.Thread(target=self.serve, daemon=True).start()

    def serve(self):
        while True:
            try:
                conn, _ = self.sock.accept()
            except OSError:
                return
            self.held.append(conn)
            if self.reply is not None:
                conn.recv(64)
                conn.sendall(self.reply)
                if not self.reply:
                    conn.close()

    def close(self):
        for c in self.held:
            c.close()
        self.sock.close()


@pytest.mark.parametrize("text, host, port", [
    ("127.0.0.1:6379", "127.0.0.1", 6379), ("localhost:1", "localhost", 1), ("head-node.example:65535",
                                                                             "head-node.example", 65535),
    ("[::1]:6379", "::1", 6379), ("ray://10.0.0.2:10001", "10.0.0.2", 10001), ("ray://head", "head", CLIENT_PORT),
    ("ray://[::1]", "::1", CLIENT_PORT), ("local", None, None), ("auto", None, None)])
def test_addresses_parse(text, host, port):
    assert parse_ray_address("ray_address", text) == RayAddress(text, host, port)


@pytest.mark.parametrize("text", ["", "1.2.3", "127.0.0.1", "127.0.0.1:0", "127.0.0.1:65536", "127.0.0.1:-1",
                                  "127.0.0.1:abc", ":6379", "host :1", "a b:1", "ray://", "ray://:1", "http://h:1",
                                  "h:1\0", "h:١٢", "h:1:2", "[::1", "LOCAL", 5, None, b"h:1", "x" * 2000 + ":1"])
def test_bad_addresses_are_refused_naming_the_parameter(text):
    with pytest.raises(InvalidParameterError) as info:
        parse_ray_address("--ray", text)
    assert info.value.name == "--ray" and "HOST:PORT" in str(info.value) and "\n" not in str(info.value)


@settings(derandomize=True, database=None, max_examples=150, deadline=None)
@given(st.one_of(st.text(max_size=12), st.from_regex(r"(ray://)?[a-z0-9.\[\]:]{0,8}:[0-9]{0,6}", fullmatch=True)))
def test_a_generated_address_parses_or_is_refused(text):
    try:
        address = parse_ray_address("ray_address", text)
    except InvalidParameterError as exc:
        assert exc.name == "ray_address" and "\n" not in str(exc)
        return
    assert address.text == text
    assert (address.host is None) == (text in ("local", "auto"))
    assert address.port is None or 1 <= address.port <= 65535


def test_an_unused_port_is_refused_at_once():
    port = unused_port()
    start = time.monotonic()
    with pytest.raises(ClusterConnectionError) as info:
        check_ray_address(f"127.0.0.1:{port}")
    assert time.monotonic() - start < 2.0
    assert info.value.address == f"127.0.0.1:{port}" and "cannot connect" in info.value.reason
    assert str(info.value).startswith(f"no Ray cluster at '127.0.0.1:{port}': ")
    with pytest.raises(ClusterConnectionError):
        check_ray_address(f"ray://localhost:{port}")


@pytest.mark.parametrize("reply, says", [(None, "did not answer within 0.3 s"), (b"HTTP/1.1 400 Bad Request\r\n\r\n",
                                                                                "does not speak gRPC"),
                                         (b"", "closed the connection")])
def test_a_server_that_is_no_ray_cluster_is_refused_within_the_timeout(reply, says):
    server = Server(reply)
    try:
        start = time.monotonic()
        with pytest.raises(ClusterConnectionError, match=says):
            check_ray_address(f"127.0.0.1:{server.port}", timeout=0.3)
        assert time.monotonic() - start < 2.0
    finally:
        server.close()


def test_a_grpc_server_passes_and_local_and_auto_reach_nothing(monkeypatch):
    server = Server(bytes([0, 0, 0, 4, 0, 0, 0, 0, 0]))  # (an HTTP/2 SETTINGS frame: what a GCS answers first)
    try:
        assert check_ray_address(f"localhost:{server.port}").port == server.port
    finally:
        server.close()
    monkeypatch.delenv("RAY_ADDRESS", raising=False)
    assert check_ray_address("local").host is None and check_ray_address("auto").host is None
    monkeypatch.setenv("RAY_ADDRESS", f"127.0.0.1:{unused_port()}")
    with pytest.raises(ClusterConnectionError, match="RAY_ADDRESS|127.0.0.1"):
        check_ray_address("auto")


def test_a_study_on_an_unreachable_cluster_fails_before_planning():
    from regrasp.study.study import run_study

    start = time.monotonic()
    with pytest.raises(RegraspError, match="no Ray cluster at '127.0.0.1:"):
        run_study(SCENARIO, 1, duration=0.05, ray_address=f"127.0.0.1:{unused_port()}")
    assert time.monotonic() - start < 5.0  # (the plan alone takes longer)
    with pytest.raises(InvalidParameterError, match="ray_address"):
        run_study(SCENARIO, 1, duration=0.05, ray_address="nowhere")
