"""Why OpenCascade could not write a file: a full disk or the file size limit, else a KernelError."""


from __future__ import annotations

import contextlib
import errno
import os
import shutil
from pathlib import Path

from torus_cad.errors import KernelError
from torus_cad.tolerances import DISK_FULL_FREE_BYTES


def write_failure(kind: str, path: Path, temp: Path) -> Exception:
    """Why OpenCascade, which reports only that it failed, could not write ``temp`` (published as ``path``).

    Looked at while the partial file is still there: a full file system or the process's file size
    limit (``ulimit -f``) is an OSError naming ``path``; anything else is a KernelError.
    """
    with contextlib.suppress(OSError):
        if shutil.disk_usage(temp.parent).free < DISK_FULL_FREE_BYTES:
            return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
    with contextlib.suppress(OSError, ValueError, ImportError):
        import resource

        limit = resource.getrlimit(resource.RLIMIT_FSIZE)[0]
        if limit != resource.RLIM_INFINITY and temp.stat().st_size >= limit:
            return OSError(errno.EFBIG, os.strerror(errno.EFBIG), str(path))
    return KernelError(f"OpenCascade could not write {kind} file {str(path)!r}")
