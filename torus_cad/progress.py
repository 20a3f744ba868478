"""Progress on a terminal: stage names with elapsed time, on stderr, only when someone is watching.

A :class:`Progress` is a callable ``progress(stage_name)``, the shape
:func:`torus_cad.propeller.build_propeller` takes as its ``progress`` argument. It prints one
line per stage to stderr when stderr is a terminal and the user did not ask for ``--quiet``;
otherwise (a pipe, a log file, CI, a test) it prints nothing, so stdout and stderr of
scripted runs stay clean::

    progress = Progress.for_terminal(quiet=args.quiet)
    propeller = build_propeller(params, progress=progress)
    progress("write")
    ...
    progress.finish()
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

#: Friendlier words for the pipeline's stage names.
STAGE_LABELS: dict[str, str] = {
    "parameters": "reading parameters",
    "section_math": "blade sections (geometry)",
    "wires": "section B-splines",
    "loft": "lofting blades",
    "fuse": "fusing blades with the hub",
    "check": "checking the solid",
    "write": "writing STEP / STL / JSON",
    "tessellate": "tessellating for the preview",
    "render": "rendering the preview",
}


class Progress:
    """Prints ``[  1.2 s] stage`` lines to ``stream`` when enabled; a no-op otherwise.

    Args:
        enabled: print or not. ``None`` (default): print only if ``stream`` is a terminal.
        stream: where to print (default ``sys.stderr``; never stdout, which carries results).
        prefix: text before each line.
    """

    def __init__(self, enabled: bool | None = None, stream: TextIO | None = None,
                 prefix: str = "torus-cad") -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = is_terminal(self.stream) if enabled is None else bool(enabled)
        self.prefix = prefix
        self.start = time.perf_counter()
        self.stages: list[str] = []

    @classmethod
    def for_terminal(cls, quiet: bool = False, stream: TextIO | None = None) -> "Progress":
        """Enabled when ``stream`` (default stderr) is a terminal and ``quiet`` is False."""
        stream = stream if stream is not None else sys.stderr
        return cls(enabled=not quiet and is_terminal(stream), stream=stream)

    @property
    def elapsed(self) -> float:
        """Seconds since this object was made."""
        return time.perf_counter() - self.start

    def __call__(self, stage: str) -> None:
        """Announce that ``stage`` starts now."""
        self.stages.append(stage)
        self._print(STAGE_LABELS.get(stage, stage.replace("_", " ")))

    def finish(self, message: str = "done") -> None:
        """Announce the end (with the total elapsed time)."""
        self._print(message)

    def _print(self, text: str) -> None:
        if not self.enabled:
            return
        self.stream.write(f"{self.prefix}: [{self.elapsed:6.1f} s] {text}\n")
        self.stream.flush()


def is_terminal(stream: TextIO) -> bool:
    """Whether ``stream`` is an interactive terminal (False for pipes, files and closed streams)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False
