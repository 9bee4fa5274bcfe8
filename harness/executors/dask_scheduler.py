"""The Dask scheduler as the driver sees it: whether an address answers as one before a client
connects to it (`_probe_scheduler`), and whether a task was cancelled because its scheduler
went (`scheduler_went`).
"""
from __future__ import annotations

import threading


def _probe_scheduler(address: str) -> None:
    """Ask ``address`` who it is before `distributed.Client` connects: the Client's handshake
    waits for ever on a server that accepts the connection and never answers as Dask (the
    dashboard's HTTP port 8787, any other service). TLS and other schemes are left to the Client."""
    import asyncio
    import socket

    import dask
    from dask.utils import parse_timedelta
    from distributed.comm import connect
    from distributed.comm.addressing import parse_address, parse_host_port
    try:
        scheme, where = parse_address(address)
    except ValueError:
        return                          # the Client names what is wrong with it
    if scheme != "tcp":
        return
    limit = float(parse_timedelta(dask.config.get("distributed.comm.timeouts.connect"), default="s"))
    try:                                # can it be reached at all?
        socket.create_connection(parse_host_port(where), timeout=limit).close()
    except (OSError, ValueError) as exc:
        raise OSError(f"cannot reach {where} ({exc})") from None
    outcome: dict = {}

    async def identity():
        comm = await connect(address, timeout=limit)
        try:
            await asyncio.wait_for(comm.write({"op": "identity"}), limit)
            return await asyncio.wait_for(comm.read(), limit)
        finally:
            comm.abort()

    def probe():                        # a thread of its own: the caller may be inside an event loop (Jupyter)
        try:
            outcome["reply"] = asyncio.run(asyncio.wait_for(identity(), 2 * limit + 1))
        except BaseException as exc:  # noqa: BLE001 - handed to the caller's thread
            outcome["error"] = exc

    t = threading.Thread(target=probe, name="dask-probe", daemon=True)
    t.start()
    t.join(2 * limit + 5)
    exc = outcome.get("error")          # it accepted a connection above: what it did with Dask's
    if t.is_alive() or isinstance(exc, asyncio.TimeoutError):
        raise TimeoutError(f"it accepts connections but gave no Dask answer within {2 * limit + 1:g} s "
                           "(is it another service, e.g. the dashboard's HTTP port?)") from None
    if isinstance(exc, OSError):        # CommClosedError too
        raise OSError(f"it accepts connections but closed Dask's without an answer ({type(exc).__name__}: "
                      f"{exc}); is it another service?") from None
    if exc is not None:                 # bytes that are not Dask's protocol (a banner read as a frame length)
        raise ValueError(f"it answered, but not in Dask's protocol ({type(exc).__name__}: {str(exc)[:100]}); "
                         "is it another service?") from None
    reply = outcome.get("reply")
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        kind = reply.get("type") if isinstance(reply, dict) else type(reply).__name__
        raise ValueError(f"it answered as a {kind}, not a scheduler")


SCHEDULER_REASONS = ("scheduler-connection-lost", "scheduler-restart")


def scheduler_went(exc: BaseException) -> bool:
    """Whether ``exc`` cancelled a task because its scheduler went (the client lost it, or it
    restarted: on the same address after a crash, or by any client's ``restart()``), not the
    task: distributed's ``FutureCancelledError.reason``."""
    return str(getattr(exc, "reason", "") or "") in SCHEDULER_REASONS
