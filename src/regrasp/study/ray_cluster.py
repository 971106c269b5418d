"""Where a study's runs go on Ray: the cluster's address, parsed (:func:`parse_ray_address`) and reached within
seconds (:func:`check_ray_address`) before Ray is asked to connect (Ray itself retries an address where no cluster
answers for ever), and the runs as Ray tasks (:func:`ray_runs`).

An address is one of

* ``"local"``: a Ray cluster started on this machine for the study;
* ``"auto"``: the cluster ``RAY_ADDRESS`` names, else the one ``ray start`` started on this machine (Ray finds it);
* ``"HOST:PORT"``: a cluster's GCS, as ``ray start --head`` prints it (a host name, an IPv4 address or a bracketed
  IPv6 one; a port in 1..65535);
* ``"ray://HOST[:PORT]"``: a cluster's Ray Client server (port 10001 by default).

A host and port (for ``"auto"``: ``RAY_ADDRESS``'s, when it is set) must take a TCP connection and answer as a gRPC
(HTTP/2) server does, a cluster's GCS or client server, each within :data:`CONNECT_TIMEOUT`; else a
:class:`~regrasp.core.exceptions.ClusterConnectionError` names the address and says why.
"""

from __future__ import annotations

import os
import re
import socket
import time
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from types import ModuleType

from ..core.exceptions import ClusterConnectionError, InvalidParameterError, MissingDependencyError

__all__ = ["AUTO", "CLIENT_PORT", "CONNECT_TIMEOUT", "LOCAL", "RayAddress", "check_ray_address", "parse_ray_address",
           "ray_runs", "require_ray"]

LOCAL = "local"
AUTO = "auto"
#: How long [s] a cluster's address may take to take a connection, then to answer it.
CONNECT_TIMEOUT = 5.0
#: Ray Client's default port (``ray://HOST``).
CLIENT_PORT = 10001

_CLIENT = "ray://"
_EXPECTED = ("'local', 'auto', a Ray cluster's HOST:PORT (port 1..65535) or ray://HOST[:PORT] (without spaces)")
_HOST = re.compile(r"^(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+)$")
#: HTTP/2's client preface and an empty SETTINGS frame: a gRPC server answers with a frame of its own, SETTINGS first.
_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])
_SETTINGS_FRAME = 4


@dataclass(frozen=True)
class RayAddress:
    """A Ray cluster's address, parsed.

    Attributes:
        text: The address as given (what ``ray.init`` gets).
        host: The host to reach (an IPv6 address without its brackets), or None (``"local"``, ``"auto"``).
        port: Its port, or None.
    """

    text: str
    host: str | None = None
    port: int | None = None


def parse_ray_address(name: str, value: object) -> RayAddress:
    """``value`` as a Ray address (module docstring), else an
    :class:`~regrasp.core.exceptions.InvalidParameterError` naming ``name``; nothing is reached."""
    if not isinstance(value, str) or not value or len(value) > 1000 \
            or any(c.isspace() or not c.isprintable() for c in value):
        raise InvalidParameterError(name, value, _EXPECTED)
    if value in (LOCAL, AUTO):
        return RayAddress(value)
    client = value.startswith(_CLIENT)
    rest = value[len(_CLIENT):] if client else value
    host, colon, port = rest.rpartition(":")
    if not colon or (rest.startswith("[") and rest.endswith("]")):  # no port
        host, port = (rest, str(CLIENT_PORT)) if client else ("", "")
    if not (port.isascii() and port.isdigit() and 1 <= int(port) <= 65535 and _HOST.match(host)):
        raise InvalidParameterError(name, value, _EXPECTED)
    return RayAddress(value, host[1:-1] if host.startswith("[") else host, int(port))


def _unanswered(host: str, port: int, timeout: float) -> str | None:
    """Why no gRPC server answers at ``host``:``port`` within ``timeout`` [s], or None."""
    where = f"[{host}]:{port}" if ":" in host else f"{host}:{port}"
    deadline = time.monotonic() + timeout
    try:
        with socket.create_connection((host, port), timeout=timeout) as sock:
            sock.sendall(_PREFACE)
            head = b""
            while len(head) < 9:
                left = deadline - time.monotonic()
                if left <= 0.0:
                    raise TimeoutError
                sock.settimeout(left)
                chunk = sock.recv(9 - len(head))
                if not chunk:
                    return f"{where} closed the connection (no gRPC server: not a Ray cluster)"
                head += chunk
    except (TimeoutError, socket.timeout):
        return f"{where} did not answer within {timeout:g} s"
    except OSError as exc:
        return f"cannot connect to {where} ({exc.strerror or exc})"
    if head[3] != _SETTINGS_FRAME:
        return f"{where} does not speak gRPC (HTTP/2): not a Ray cluster"
    return None


def check_ray_address(value: object, *, name: str = "ray_address", timeout: float = CONNECT_TIMEOUT) -> RayAddress:
    """``value`` parsed (:func:`parse_ray_address`) and, when it names a host (for ``"auto"``: when ``RAY_ADDRESS``
    does), reached: a gRPC server must answer there within ``timeout`` [s].

    Raises:
        InvalidParameterError: not an address.
        ClusterConnectionError: nothing, or no gRPC server, answers there in time.
    """
    address = parse_ray_address(name, value)
    target = address
    if address.text == AUTO and os.environ.get("RAY_ADDRESS"):
        target = parse_ray_address("RAY_ADDRESS", os.environ["RAY_ADDRESS"])
    if target.host is not None:
        reason = _unanswered(target.host, target.port, timeout)
        if reason is not None:
            raise ClusterConnectionError(target.text, reason)
    return address


def require_ray() -> ModuleType:
    """The ``ray`` module, or a :class:`~regrasp.core.exceptions.MissingDependencyError` naming the extra."""
    try:
        import ray
    except ImportError as exc:
        raise MissingDependencyError("ray", "ray", "a study on Ray") from exc
    return ray


def ray_runs(address: str, workers: int | None, function: Callable, shared: tuple, items: Sequence) -> Iterator:
    """``function(shared[0], item, *shared[1:])`` for each item, as Ray tasks of one CPU on the cluster at
    ``address`` (checked with :func:`check_ray_address` already; ``"local"``: one started here with ``workers``
    CPUs, shut down after), as they finish. Closing the generator early cancels the tasks still pending or running.
    Ray's own refusal to connect is a :class:`~regrasp.core.exceptions.ClusterConnectionError`."""
    ray = require_ray()
    started = not ray.is_initialized()
    if started:
        kwargs = {"num_cpus": workers} if address == LOCAL and workers is not None else {}
        try:
            ray.init(address=address, include_dashboard=False, log_to_driver=False, logging_level="ERROR", **kwargs)
        except (ConnectionError, TimeoutError, ValueError) as exc:  # (Ray's: no cluster found, a bad address...)
            raise ClusterConnectionError(address, f"Ray could not connect ({' '.join(str(exc).split())})") from exc
    pending: list = []
    try:
        task = ray.remote(num_cpus=1)(function)
        refs = [ray.put(x) for x in shared]
        pending = [task.remote(refs[0], item, *refs[1:]) for item in items]
        while pending:
            (done,), pending = ray.wait(pending, num_returns=1)
            yield ray.get(done)
    finally:
        for ref in pending:  # (an early close: Ctrl-C, or the consumer stopped)
            ray.cancel(ref, force=True)
        if started:
            ray.shutdown()
