"""Reaching an existing Dask scheduler (``--scheduler ADDRESS``, ``--scheduler-file FILE``): a named error, never a hang.

Whatever is at the other end -- a malformed address, an unknown scheme, a
scheduler file that is missing, not JSON or holds no address, nothing
listening, a server of another kind (HTTP, ...), a listener that accepts and
never answers, a Dask worker -- reaching it ends within one bound, the
connect timeout (:data:`DEFAULT_CONNECT_TIMEOUT_S`, ``--connect-timeout``),
with one :class:`SchedulerError` naming what was found (the command's exit
status 2: the address given does not lead to a scheduler):

1. :func:`check_address` and :func:`read_scheduler_file` check the address
   (scheme, host, port) and read the file whole, without the network: a bad
   one is refused at once, when the options are made.
2. :func:`probe` resolves the host, opens a TCP connection (retried while it
   is refused, until the deadline: a scheduler may be starting), then speaks
   Dask's handshake and asks for the scheduler's identity.  Only a process
   that answers as a Dask scheduler passes.
3. Only then does :class:`RemoteDask` make a ``distributed.Client``, within
   what is left of the timeout.

Steps 2 and 3 run in daemon helper threads
(:func:`~simgrip.parallel.helper_thread.call_in_helper`): the calling thread
only waits, so Ctrl-C or SIGTERM stops it at once (also during the connect),
and process exit never waits for a helper still connecting.  A Client that
failed or was given up on is made inert (:func:`forget_client`), so that no
``Client.__del__`` waits 20 s at exit for a scheduler that never answered
(the ``Exception ignored in Client.__del__ ... TimeoutError`` of issue 16).

A scheduler without workers: :class:`WorkerWatch` fails the run with a named
:class:`~simgrip.parallel.errors.RunnerError` (exit status 1) once the
scheduler has had no worker for :data:`DEFAULT_WORKER_WAIT_S`
(``--worker-wait``), at the start or when every worker has gone later, instead
of waiting at 0 % forever.  Workers that join within the wait are used.

``distributed`` is imported inside the functions that need it.
"""

from __future__ import annotations

import contextlib
import json
import math
import re
import socket
import time
from pathlib import Path

from simgrip.parallel.errors import RunnerError, SchedulerError
from simgrip.parallel.helper_thread import HelperTimeout, call_in_helper

__all__ = [
    "DEFAULT_CONNECT_TIMEOUT_S",
    "DEFAULT_WORKER_WAIT_S",
    "SchedulerError",
    "check_seconds",
    "check_address",
    "read_scheduler_file",
    "probe",
    "forget_client",
    "RemoteDask",
    "WorkerWatch",
]

#: Seconds allowed to reach a scheduler (resolve, connect, handshake, identity, client): Dask's own default is 30 s;
#: 10 s is ample on any network a cluster runs on, and short enough that a wrong address is said quickly.
DEFAULT_CONNECT_TIMEOUT_S = 10.0
#: Largest accepted connect timeout [s].
MAX_CONNECT_TIMEOUT_S = 3600.0
#: Seconds a reached scheduler may have no worker before the run fails (workers of a batch system may take a while
#: to start: ``--worker-wait inf`` waits for ever).
DEFAULT_WORKER_WAIT_S = 30.0
#: Seconds between two questions to the scheduler about its workers while nothing completes.
WORKER_POLL_S = 1.0
#: Largest scheduler file read [bytes] (dask's are ~1 kB).
MAX_SCHEDULER_FILE_BYTES = 1 << 20
#: Seconds allowed to close a client.
CLOSE_TIMEOUT_S = 1.0

#: Address schemes over TCP, whose addresses are ``HOST:PORT``.
TCP_SCHEMES = ("tcp", "tls", "ws", "wss")
_HOSTNAME = re.compile(r"[A-Za-z0-9_](?:[A-Za-z0-9_.-]*[A-Za-z0-9_])?")
_IPV6 = re.compile(r"[0-9A-Fa-f:.]+(?:%[A-Za-z0-9_.-]+)?")
EXAMPLE = "tcp://127.0.0.1:8786"


def check_seconds(value, name: str, *, upper: float = math.inf, allow_inf: bool = False) -> float:
    """``value`` as seconds in (0, ``upper``] (``inf`` too where ``allow_inf``); ``ValueError`` naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{name} must be a number of seconds, got {value!r}")
    value = float(value)
    if math.isnan(value) or value <= 0 or (value > upper and not (allow_inf and math.isinf(value))):
        bound = f"(0, {upper:g}]" + (" or inf" if allow_inf else "")
        raise ValueError(f"{name} must be a number of seconds in {bound}, got {value!r}")
    return value


def _split(address: str) -> tuple[str, str]:
    scheme, sep, loc = address.partition("://")
    return (scheme, loc) if sep else ("tcp", address)  # dask reads an address without a scheme as tcp


def _host_port(loc: str, given: str, option: str) -> tuple[str, int]:
    """``(host, port)`` of ``HOST:PORT`` or ``[IPv6]:PORT``; ``SchedulerError`` naming ``option`` otherwise."""
    def bad(why: str):
        return SchedulerError(f"{option} must be an address such as {EXAMPLE}, got {given!r} ({why})")

    if loc.startswith("["):
        host, sep, tail = loc[1:].partition("]")
        if not sep or not _IPV6.fullmatch(host):
            raise bad("not an IPv6 address in brackets")
        port = tail[1:] if tail.startswith(":") else None
    else:
        host, sep, port = loc.rpartition(":")
        if not sep:
            raise bad("no port")
        if ":" in host:
            raise bad("an IPv6 address needs brackets, e.g. tcp://[::1]:8786")
        if not _HOSTNAME.fullmatch(host):
            raise bad("not a host name or IP address" if host else "no host")
    if port is None or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise bad("no port" if not port else "the port must be an integer in 1 ... 65535")
    return host, int(port)


def check_address(address, option: str = "scheduler") -> str:
    """The scheduler address ``address``, checked without the network; ``SchedulerError`` naming ``option``.

    ``SCHEME://HOST:PORT`` (``tcp``, ``tls``, ``ws``, ``wss``; no scheme reads
    as ``tcp``), or another scheme that distributed knows (``ucx``);
    ``inproc`` is refused (it exists only inside one process).  Returns the
    address stripped of surrounding blanks.
    """
    if not isinstance(address, str) or not address.strip():
        raise SchedulerError(f"{option} must be an address such as {EXAMPLE}, got {address!r}")
    address = address.strip()
    scheme, loc = _split(address)
    if scheme in TCP_SCHEMES:
        _host_port(loc, address, option)
        return address
    if scheme == "inproc":
        raise SchedulerError(f"{option} {address!r}: inproc:// addresses exist only inside one Python process; "
                             f"give the scheduler's network address, e.g. {EXAMPLE}")
    from distributed.comm.registry import get_backend

    try:
        get_backend(scheme)
    except Exception:  # distributed: ValueError "unknown address scheme"; a plug-in may fail otherwise
        raise SchedulerError(f"{option} {address!r} has an unknown address scheme {scheme!r} "
                             f"(known: {', '.join(TCP_SCHEMES)}), e.g. {EXAMPLE}") from None
    if not loc:
        raise SchedulerError(f"{option} must be an address such as {EXAMPLE}, got {address!r} (no location)")
    return address


def read_scheduler_file(path) -> str:
    """The address in the scheduler file ``path`` (``dask scheduler --scheduler-file FILE``), checked.

    ``SchedulerError`` naming ``scheduler-file`` when the file is missing, not
    a regular file, larger than :data:`MAX_SCHEDULER_FILE_BYTES`, not UTF-8
    JSON, or holds no ``"address"`` string.  Unlike ``distributed.Client``,
    a missing file is not waited for.
    """
    name = f"scheduler-file {str(path)!r}"
    p = Path(path)
    try:
        if not p.exists():
            raise SchedulerError(f"{name} does not exist (dask scheduler --scheduler-file FILE writes it)")
        if not p.is_file():
            raise SchedulerError(f"{name} is not a regular file")
        if p.stat().st_size > MAX_SCHEDULER_FILE_BYTES:
            raise SchedulerError(f"{name} is not a scheduler file (larger than {MAX_SCHEDULER_FILE_BYTES} bytes)")
        text = p.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise SchedulerError(f"{name} is not a scheduler file (not UTF-8 text)") from None
    except OSError as exc:
        raise SchedulerError(f"{name} cannot be read: {exc.strerror or exc}") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise SchedulerError(f"{name} is not a scheduler file (not JSON: {exc.msg} at line {exc.lineno})") from None
    address = data.get("address") if isinstance(data, dict) else None
    if not isinstance(address, str) or not address.strip():
        raise SchedulerError(f"{name} holds no scheduler address (JSON with an \"address\" such as {EXAMPLE!r}, "
                             "as dask scheduler --scheduler-file writes)")
    try:
        return check_address(address, "its address")
    except SchedulerError as exc:
        raise SchedulerError(f"{name} holds no usable scheduler address: {exc}") from None


# probing ------------------------------------------------------------------------------------

def _tcp_connect(host: str, port: int, label: str, deadline: float, timeout: float) -> None:
    """Open (and close) one TCP connection to ``host:port``, retrying refusals until ``deadline``."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        why = exc.strerror if isinstance(exc, socket.gaierror) else str(exc)
        raise SchedulerError(f"{label} cannot be reached: host {host!r} not found ({why})") from None
    last, pause = None, 0.05
    while True:
        for family, kind, proto, _, addr in infos:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            try:
                with socket.socket(family, kind, proto) as s:
                    s.settimeout(left)
                    s.connect(addr)
                return
            except OSError as exc:  # refused, unreachable, timed out
                last = exc
        left = deadline - time.monotonic()
        if left <= 0:
            why = "connection refused" if isinstance(last, ConnectionRefusedError) else (
                "no answer" if last is None or isinstance(last, TimeoutError) else (last.strerror or str(last)))
            raise SchedulerError(f"{label} cannot be reached: nothing accepted a connection within {timeout:g} s "
                                 f"({why}); is the Dask scheduler running at this address?")
        time.sleep(min(pause, left))
        pause = min(2 * pause, 0.5)


async def _identity(address: str, deadline: float, connection_args: dict) -> dict:
    import asyncio

    from distributed.comm import connect

    comm = await asyncio.wait_for(connect(address, timeout=max(0.01, deadline - time.monotonic()), **connection_args),
                                  max(0.01, deadline - time.monotonic()))
    try:
        await asyncio.wait_for(comm.write({"op": "identity", "reply": True, "close": True}),
                               max(0.01, deadline - time.monotonic()))
        return await asyncio.wait_for(comm.read(), max(0.01, deadline - time.monotonic()))
    finally:
        comm.abort()


def _probe(address: str, label: str, deadline: float, timeout: float) -> dict:
    import asyncio

    from distributed.comm.core import CommClosedError
    from distributed.security import Security

    scheme, loc = _split(address)
    if scheme in TCP_SCHEMES:
        host, port = _host_port(loc, address, "scheduler")
        _tcp_connect(host, port, label, deadline, timeout)
    try:
        info = asyncio.run(_identity(address, deadline, Security().get_connection_args("client")))
    except (asyncio.TimeoutError, TimeoutError):
        raise SchedulerError(f"{label} is not a Dask scheduler: it accepted a connection but gave no Dask answer "
                             f"within {timeout:g} s (another kind of server?)") from None
    except CommClosedError:
        raise SchedulerError(f"{label} is not a Dask scheduler: it closed the connection without a Dask "
                             "handshake (another kind of server?)") from None
    except OSError as exc:  # it accepted the TCP check, then no connection (it went away meanwhile)
        raise SchedulerError(f"{label} cannot be reached: {exc.strerror or exc}"[:400]) from None
    except Exception as exc:  # garbage where Dask's frames belong, a refused TLS handshake, ...
        raise SchedulerError(f"{label} is not a Dask scheduler: its answer is not Dask's protocol "
                             f"({type(exc).__name__}: {exc})"[:400]) from None
    kind = info.get("type") if isinstance(info, dict) else None
    if not isinstance(kind, str) or not kind.endswith("Scheduler") or "workers" not in info:
        what = f"a Dask {kind}" if isinstance(kind, str) else "not Dask's"
        raise SchedulerError(f"{label} answers, but as {what}, not as a Dask scheduler (give the scheduler's "
                             "address)")
    return info


def probe(address: str, timeout: float = DEFAULT_CONNECT_TIMEOUT_S, *, label: str | None = None) -> dict:
    """The identity of the Dask scheduler at ``address`` (its ``"workers"``, ...), or a named ``SchedulerError``.

    Resolves the host, connects (refusals retried until the deadline), speaks
    Dask's handshake and asks the scheduler who it is, in a daemon thread,
    all within ``timeout`` seconds; this thread waits interruptibly.  No
    ``Client`` is made.  Errors begin with ``label`` (default ``scheduler
    ADDRESS``: the option that gave it).
    """
    address = check_address(address)
    label = label or f"scheduler {address}"
    timeout = check_seconds(timeout, "connect-timeout", upper=MAX_CONNECT_TIMEOUT_S)
    deadline = time.monotonic() + timeout
    try:
        # the probe keeps its own deadline; the extra second only covers a resolver that ignores it
        return call_in_helper(lambda: _probe(address, label, deadline, timeout), name="simgrip-scheduler-probe",
                              timeout=timeout + 1.0)
    except HelperTimeout:
        raise SchedulerError(f"{label} cannot be reached within {timeout:g} s (the host name did not resolve in "
                             "time?)") from None


# the client ----------------------------------------------------------------------------------

def forget_client(client) -> None:
    """Make a ``Client`` that failed, or that was given up on, inert: its ``close()`` and ``__del__`` return at once.

    distributed's ``Client.__del__`` closes a client that is not ``closed``
    and waits up to twice its timeout for a scheduler that may never answer,
    then prints ``Exception ignored in Client.__del__``; its event-loop
    thread is stopped (briefly) so that nothing of it keeps running.
    """
    if client is None:
        return
    with contextlib.suppress(Exception):
        client.status = "closed"
    runner = getattr(client, "_loop_runner", None)
    if runner is not None:
        with contextlib.suppress(Exception):
            runner.stop(timeout=CLOSE_TIMEOUT_S)


def close_client(client, timeout: float = CLOSE_TIMEOUT_S) -> None:
    """Close ``client`` within about ``timeout`` seconds, quietly, and leave it inert whatever happened."""
    with contextlib.suppress(Exception):
        client.close(timeout=timeout)
    forget_client(client)


def _make_client(address: str, timeout: float):
    """A ``Client`` of ``address``; one that fails while connecting is made inert before the error propagates."""
    from distributed import Client

    client = Client.__new__(Client)  # kept, so that a half-made client can be made inert
    try:
        client.__init__(address, timeout=timeout, set_as_default=False)
    except BaseException:
        forget_client(client)
        raise
    return client


class RemoteDask:
    """A Client of an existing cluster (``scheduler`` address or ``scheduler_file``), reached within ``timeout``;
    :meth:`stop` cancels this call's work (``futures``) and disconnects, leaving the cluster running.

    Raises :class:`SchedulerError` when nothing answers as a scheduler there,
    :class:`~simgrip.parallel.errors.RunnerError` when it answered but a
    client could not connect, ``KeyboardInterrupt`` at once on an interrupt.
    """

    def __init__(self, scheduler: str | None = None, scheduler_file: str | None = None,
                 timeout: float = DEFAULT_CONNECT_TIMEOUT_S):
        timeout = check_seconds(timeout, "connect-timeout", upper=MAX_CONNECT_TIMEOUT_S)
        if scheduler is not None:
            address = check_address(scheduler)
            self.where, label = address, f"scheduler {address}"
        else:
            address = read_scheduler_file(scheduler_file)
            self.where = f"{address} (scheduler file {scheduler_file})"
            label = f"scheduler-file {str(scheduler_file)!r} (address {address})"
        self.address = address
        t0 = time.monotonic()
        self.identity = probe(address, timeout, label=label)
        left = max(1.0, timeout - (time.monotonic() - t0))
        try:
            self.client = call_in_helper(lambda: _make_client(address, left), name="simgrip-dask-client",
                                         timeout=left + 1.0, discard=close_client)
        except HelperTimeout:
            raise RunnerError(f"the Dask scheduler at {self.where} answered, but a client could not connect "
                              f"within {left:.3g} s") from None
        except Exception as exc:  # OSError, TimeoutError, a version mismatch, ...
            raise RunnerError(f"the Dask scheduler at {self.where} answered, but a client could not connect: "
                              f"{type(exc).__name__}: {exc}") from None
        self.futures = []

    def stop(self, interrupted: bool) -> None:
        """Cancel this run's tasks (after an interrupt or failure) and disconnect, within ~2 s; the cluster stays."""
        client = self.client

        def close():
            with contextlib.suppress(Exception):
                if interrupted and self.futures:
                    client.cancel(self.futures, force=True)
            with contextlib.suppress(Exception):
                client.close(timeout=CLOSE_TIMEOUT_S)

        import threading

        closer = threading.Thread(target=close, name="simgrip-dask-disconnect", daemon=True)
        closer.start()
        closer.join(2 * CLOSE_TIMEOUT_S)
        if getattr(client, "status", None) != "closed":
            forget_client(client)


#: What a run without workers says by default (an existing cluster); the local cluster says its own.
START_WORKERS = "start workers for it (dask worker ADDRESS), or wait longer with --worker-wait SECONDS"


class WorkerWatch:
    """Fails a run on a cluster that has had no worker for ``wait_s`` seconds.

    :meth:`check` is called while the run waits for results; at most every
    :data:`WORKER_POLL_S` it asks the scheduler how many workers it has.  A
    question that fails (the scheduler gone) counts as no answer, not as no
    worker: the run's futures report a lost scheduler themselves.  ``where``
    names the cluster and ``hint`` says what to do, in the error.
    """

    def __init__(self, client, where: str, wait_s: float, *, workers: int | None = None, clock=time.monotonic,
                 hint: str = START_WORKERS):
        self.client, self.where, self.wait_s, self.clock, self.hint = client, where, wait_s, clock, hint
        now = clock()
        self.asked = now
        self.empty_since = now if workers == 0 else None

    def _count(self) -> int | None:
        try:
            try:
                info = self.client.scheduler_info(n_workers=0)
            except TypeError:  # distributed before n_workers
                info = self.client.scheduler_info()
        except Exception:
            return None
        n = info.get("n_workers")
        return n if isinstance(n, int) else len(info.get("workers", {}))

    def check(self) -> None:
        """Raise ``RunnerError`` once the scheduler has had no worker for ``wait_s`` seconds."""
        now = self.clock()
        if now - self.asked >= WORKER_POLL_S:
            self.asked = now
            n = self._count()
            if n is not None:
                self.empty_since = (self.empty_since if self.empty_since is not None else now) if n == 0 else None
        if self.empty_since is not None and now - self.empty_since >= self.wait_s:
            raise RunnerError(f"{self.where} has had no workers for {self.wait_s:g} s: {self.hint}")
