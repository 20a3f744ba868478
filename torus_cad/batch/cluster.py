"""A Dask distributed cluster as the batch's executor: connect, describe, close.

The runner drives ``Client.get_executor()`` exactly like the local pool. On a cluster the
output folder must be on a file system every worker can write and this machine can read, the
workers need torus_cad installed, and each should run one thread (``dask worker ADDRESS
--nthreads 1``). The per-design time limit is not enforced there.
"""

from __future__ import annotations

import os
from typing import Any

from torus_cad.batch.runner import BatchError

__all__ = ["CONNECT_TIMEOUT_S", "client_label", "close_client", "connect"]

CONNECT_TIMEOUT_S = 20.0  #: how long to wait for a Dask scheduler, s


def connect(scheduler: str, workers: int | None) -> tuple[Any, Any]:
    """A client of the scheduler at ``scheduler``, or of a new LocalCluster of ``workers`` processes
    (``"local"``).

    Returns the client and the LocalCluster it started (None for a remote scheduler); close
    both with :func:`close_client`.
    """
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        from torus_cad.runtime.extras import missing_extra_message

        raise BatchError(
            missing_extra_message("--scheduler", "sweep", "dask.distributed")
        ) from None
    try:
        if scheduler == "local":
            cluster = LocalCluster(
                n_workers=workers or os.cpu_count() or 1,  # type: ignore[no-untyped-call]
                threads_per_worker=1,
                processes=True,
                dashboard_address=None,
            )
            return Client(cluster), cluster  # type: ignore[no-untyped-call]
        return Client(scheduler, timeout=f"{CONNECT_TIMEOUT_S}s"), None  # type: ignore[no-untyped-call]
    except (OSError, TimeoutError, ValueError) as error:
        raise BatchError(
            f"cannot connect to the Dask scheduler at {scheduler!r}: {error}"
        ) from None


def close_client(client: Any, cluster: Any) -> None:
    """Close a client from :func:`connect` and its LocalCluster (if any)."""
    client.close()
    if cluster is not None:
        cluster.close()


def client_label(client: Any) -> str:
    """``"ADDRESS, N workers, M threads"`` for the summary."""
    try:
        info = client.scheduler_info()
        workers = info.get("workers", {})
        threads = sum(worker.get("nthreads", 1) for worker in workers.values())
        return f"{info.get('address', '?')}, {len(workers)} workers, {threads} threads"
    except Exception:
        return "cluster"
