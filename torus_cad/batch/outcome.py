"""What happened to one design of a batch (a sweep or a fuzz run): one enum for both.

Old names, for readers of older tables and notes: the sweep's ``ok`` is now ``valid``; the
fuzzer's ``kernel`` is ``failed`` and its ``exception`` is ``error``; a worker process that
died, which a sweep used to record as ``error``, is ``crash``.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class Outcome(StrEnum):
    """The outcome of one design, as written in the results table's ``status`` column."""

    VALID = "valid"  #: one valid closed solid (and its files, when written)
    REFUSED = "refused"  #: ParameterError or GeometryError: the package's own one-line refusal
    FAILED = "failed"  #: KernelError: OpenCascade failed on a design the checks let through
    ERROR = "error"  #: any other exception (a bug, a file that cannot be written, no memory)
    BAD_FILE = "bad_file"  #: built, but a written file is missing, partial or does not read back
    TIMEOUT = "timeout"  #: ran past the per-design time limit; its worker was killed
    CRASH = "crash"  #: the worker process died (a segfault inside OpenCascade, the OOM killer)
    PENDING = "pending"  #: not run (yet): the batch was interrupted before it

    @property
    def acceptable(self) -> bool:
        """A valid solid or a clear refusal: what every in-range design should give."""
        return self in (Outcome.VALID, Outcome.REFUSED)

    @property
    def done(self) -> bool:
        """Finished for good: a resumed sweep skips it (everything else is tried again)."""
        return self in (Outcome.VALID, Outcome.REFUSED)

    @property
    def problem(self) -> bool:
        """Neither acceptable nor pending: makes a sweep exit non-zero and a fuzz run fail."""
        return not self.acceptable and self is not Outcome.PENDING


#: Outcomes that come from a design (not from an interrupted run), in table order.
RUN_OUTCOMES = tuple(outcome for outcome in Outcome if outcome is not Outcome.PENDING)


@dataclass(frozen=True)
class DesignResult:
    """One design's outcome, as a worker sends it back (plain data: it pickles to any worker).

    Attributes:
        design_id: the design's id (sweeps) or name (fuzzing).
        outcome: what happened.
        reason: the one-line refusal or error message ('' for a valid design).
        seconds: wall time of the build, the writes and the checks, s.
        detail: a traceback or other text for a problem outcome ('' otherwise).
        error: the exception's class name (``GeometryError``, ``KernelError``, ...), '' when none.
        prescreened: refused by the kernel-free checks in the batch's own process, before any worker
            built it (:func:`torus_cad.batch.job.prescreen`); False for every other outcome.
    """

    design_id: str
    outcome: Outcome
    reason: str = ""
    seconds: float = 0.0
    detail: str = ""
    error: str = ""
    prescreened: bool = False


def tally(results: list[DesignResult] | tuple[DesignResult, ...]) -> dict[Outcome, int]:
    """Counts per outcome, every outcome present (zeros included)."""
    counts = dict.fromkeys(Outcome, 0)
    for result in results:
        counts[result.outcome] += 1
    return counts
