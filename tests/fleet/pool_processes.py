"""The worker processes of a campaign's local pool, seen from outside (psutil)."""

from __future__ import annotations

from typing import Any


def pool_workers(psutil: Any, client_pid: int) -> list[Any]:
    """The pool workers of the client process `client_pid`: the children of its fork server (the client's child
    running ``multiprocessing.forkserver``; `gyrodrift.fleet.executor._pool_context`), or spawned children where
    the platform has no fork server."""
    workers = []
    for child in psutil.Process(client_pid).children():
        cmdline = " ".join(child.cmdline())
        if "forkserver" in cmdline:
            workers.extend(child.children())
        elif "spawn" in cmdline:
            workers.append(child)
    return workers
