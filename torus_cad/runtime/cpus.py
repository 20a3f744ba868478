"""The CPUs this process may use, and the thread and worker counts the command line allows on them.

Standard library and torus_cad.tolerances only: the command line's parser shows these ranges in
``--help`` before anything heavy is imported.
"""

from __future__ import annotations

import os

from torus_cad.tolerances import (
    CFD_THREADS_LIMIT,
    CFD_THREADS_PER_CPU,
    WORKERS_LIMIT,
    WORKERS_PER_CPU,
)


def available_cpus() -> int:
    """The CPUs this process may run on: its affinity mask (a container's or taskset's share), else
    all."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not Linux
        return max(1, os.cpu_count() or 1)


def max_cfd_threads() -> int:
    """Most gmsh threads (``cfd --threads``): CFD_THREADS_PER_CPU per CPU, at most
    CFD_THREADS_LIMIT."""
    return min(CFD_THREADS_LIMIT, CFD_THREADS_PER_CPU * available_cpus())


def max_workers() -> int:
    """Most worker processes (``sweep`` / ``optimize --workers``): WORKERS_PER_CPU per CPU, at most
    WORKERS_LIMIT."""
    return min(WORKERS_LIMIT, WORKERS_PER_CPU * available_cpus())
