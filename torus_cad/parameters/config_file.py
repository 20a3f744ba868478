"""Reading a configuration file safely: only a regular file, only up to a size limit, UTF-8 (BOM allowed).

The reading itself is torus_cad.input_files's, shared with every other file a design names
(airfoil coordinate files, sweep files): ``/dev/zero``, a named pipe, a socket or a folder is
refused at once (opened non-blocking, checked with ``fstat``), so the command can neither read
gigabytes nor wait forever.
"""

from __future__ import annotations

from pathlib import Path

from torus_cad.input_files import read_untrusted_text
from torus_cad.tolerances import CONFIG_FILE_MAX_BYTES


def read_config_text(path: str | Path, what: str = "configuration", max_bytes: int = CONFIG_FILE_MAX_BYTES) -> str:
    """The text of the configuration file ``path``, or ParameterError (exit 2) naming it and the reason.

    Refused: anything but a regular file (folder, device, named pipe, socket), a file over
    ``max_bytes``, text that is not UTF-8, and an empty (or whitespace-only) file. A UTF-8 byte
    order mark, as some Windows editors write, is accepted and dropped. ``what`` names the file's
    role in messages ("configuration", "sweep file").
    """
    return read_untrusted_text(path, what, max_bytes)
