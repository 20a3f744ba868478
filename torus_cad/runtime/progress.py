"""Progress on a terminal, drawn with rich: build stages, and a bar for sweeps and fuzz runs.

Both displays write to stderr, and only when it is an interactive terminal and the user did
not ask for ``--quiet``; otherwise (a pipe, a log file, CI, a test) they print nothing, so
the output of scripted runs stays clean. rich is imported only when something is drawn.

* :class:`StageProgress` is a callable ``progress(stage_name)``, the shape
  :func:`torus_cad.propeller.build_propeller` takes as its ``progress`` argument: one line per
  stage with the elapsed time. ``torus-cad build`` starts it before importing the kernel, so
  a terminal shows a line within a fraction of a second of the command starting::

      progress = StageProgress.for_terminal(quiet=args.quiet)
      progress(Stage.KERNEL_IMPORT)
      from torus_cad.propeller import build_propeller
      propeller = build_propeller(params, progress=progress)
      progress.finish()

* :class:`BatchProgress` is one bar for a batch of designs: done / total, the count of each
  outcome, designs per minute and the time left.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Mapping
from typing import Any, Self, TextIO

__all__ = ["HEARTBEAT_S", "BatchProgress", "StageProgress", "is_terminal"]

#: Seconds without a line after which :meth:`StageProgress.heartbeat` says the stage still runs.
HEARTBEAT_S = 30.0


def is_terminal(stream: TextIO) -> bool:
    """Whether ``stream`` is an interactive terminal (False for pipes, files and closed streams)."""
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def _console(stream: TextIO) -> Any:
    """A rich Console on ``stream`` (imported here: rich costs import time only when it draws)."""
    from rich.console import Console

    return Console(file=stream, highlight=False, soft_wrap=True)


class StageProgress:
    """Prints ``torus-cad: [  1.2 s] stage`` lines when enabled; records the stages either way.

    Args:
        enabled: draw or not. ``None`` (default): draw only if ``stream`` is a terminal.
        stream: where to draw (default ``sys.stderr``; never stdout, which carries results).
        prefix: text before each line.
    """

    def __init__(
        self, enabled: bool | None = None, stream: TextIO | None = None, prefix: str = "torus-cad"
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = is_terminal(self.stream) if enabled is None else bool(enabled)
        self.prefix = prefix
        self.start = time.perf_counter()
        self.stages: list[str] = []
        self._console = _console(self.stream) if self.enabled else None
        self._stage_start = self._last_line = self.start

    @classmethod
    def for_terminal(cls, quiet: bool = False, stream: TextIO | None = None) -> StageProgress:
        """Enabled when ``stream`` (default stderr) is a terminal and ``quiet`` is False."""
        stream = stream if stream is not None else sys.stderr
        return cls(enabled=not quiet and is_terminal(stream), stream=stream)

    @property
    def elapsed(self) -> float:
        """Seconds since this object was made."""
        return time.perf_counter() - self.start

    def __call__(self, stage: str) -> None:
        """Announce that ``stage`` starts now: a build stage in its words (its ``label``); another
        pipeline's stage (``MeshStage``, ``CfdStage``) or an OpenFOAM command of ``simulate`` as its
        name, with spaces."""
        self.stages.append(stage)
        self._stage_start = time.perf_counter()
        self._print(self._label(stage))

    @staticmethod
    def _label(stage: str) -> str:
        label = getattr(stage, "label", None)  # a build stage (torus_cad.build_stages) has words
        return label if isinstance(label, str) else str(stage).replace("_", " ")

    def heartbeat(self, every_s: float = HEARTBEAT_S) -> None:
        """When no line came for ``every_s`` seconds: one line saying the current stage still runs
        and for how long (a long gmsh call prints nothing itself). Call it often; it prints at most
        every ``every_s``."""
        now = time.perf_counter()
        if not self.stages or now - self._last_line < every_s:
            return
        self._print(
            f"{self._label(self.stages[-1])}: still running, "
            f"{now - self._stage_start:.0f} s in this stage"
        )

    def finish(self, message: str = "done") -> None:
        """Announce the end (with the total elapsed time)."""
        self._print(message)

    def _print(self, text: str) -> None:
        self._last_line = time.perf_counter()
        if self._console is None:
            return
        from rich.text import Text

        self._console.print(
            Text.assemble(f"{self.prefix}: ", (f"[{self.elapsed:6.1f} s]", "dim"), f" {text}")
        )


class BatchProgress:
    """One bar for a batch: ``done/total``, outcome counts, designs per minute, time left.

    Args:
        total: designs in the batch.
        already_done: designs finished before this run (a resumed sweep); they start the bar.
        enabled: draw or not; ``None``: only when ``stream`` is a terminal.
        stream: where to draw (default stderr).
        label: the text before the bar.

    Use as a context manager, or call :meth:`close` at the end.
    """

    def __init__(
        self,
        total: int,
        already_done: int = 0,
        enabled: bool | None = None,
        stream: TextIO | None = None,
        label: str = "designs",
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = is_terminal(self.stream) if enabled is None else bool(enabled)
        self.total, self.already_done = total, already_done
        self.counts: dict[str, int] = {}
        self.start = time.perf_counter()
        self._bar: Any = None
        if self.enabled:
            self._bar, self._task = self._make_bar(label)

    def _make_bar(self, label: str) -> tuple[Any, Any]:
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeRemainingColumn,
        )

        bar = Progress(
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[counts]}"),
            TextColumn("{task.fields[rate]}"),
            TimeRemainingColumn(),
            console=_console(self.stream),
            refresh_per_second=4,
        )
        task = bar.add_task(
            label, total=self.total, completed=self.already_done, counts="", rate=""
        )
        bar.start()
        return bar, task

    @property
    def built(self) -> int:
        """Designs finished in this run (any outcome)."""
        return sum(self.counts.values())

    def rate_per_minute(self) -> float:
        """Designs finished in this run per minute of wall time so far."""
        elapsed = time.perf_counter() - self.start
        return 60.0 * self.built / elapsed if elapsed > 0 else 0.0

    def update(self, outcome: str) -> None:
        """Count one finished design (``outcome`` is its status name) and redraw."""
        self.counts[str(outcome)] = self.counts.get(str(outcome), 0) + 1
        if self._bar is not None:
            self._bar.update(
                self._task,
                advance=1,
                counts=_counts_text(self.counts),
                rate=f"{self.rate_per_minute():.1f}/min",
            )

    def message(self, text: str) -> None:
        """Print one line above the bar (only when the bar is drawn)."""
        if self._bar is not None:
            from rich.text import Text

            self._bar.console.print(Text(text))

    def close(self) -> None:
        """Stop drawing; the last state of the bar stays on the terminal."""
        if self._bar is not None:
            self._bar.stop()
            self._bar = None

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _counts_text(counts: Mapping[str, int]) -> str:
    return "  ".join(f"{name} {count}" for name, count in counts.items() if count)
