"""The package's exceptions: one base, one subclass per kind of failure.

The CLI maps :class:`ParameterError` (with :class:`BudgetError`) and :class:`GeometryError` to
exit code 2 (bad input), :class:`MissingExtraError` to exit code 2 as well (nothing was tried), every other :class:`TorusCadError` to exit code 1 (the kernel or the
file system failed; :class:`IncompleteOutputError` is ``torus-cad verify`` finding a broken set).
"""


class TorusCadError(Exception):
    """Base of every error torus_cad raises on purpose."""


class ParameterError(TorusCadError, ValueError):
    """A design parameter or configuration file is invalid; the message names the field."""


class BudgetError(ParameterError):
    """The parameters ask for work over a documented limit (e.g. an STL of too many triangles); refused before it starts."""


class GeometryError(TorusCadError):
    """The parameters are valid one by one but describe no sound propeller (e.g. a Frenet frame is undefined)."""


class KernelError(TorusCadError):
    """OpenCascade failed to build, check or export the solid."""


class OutputError(TorusCadError):
    """An output file or folder could not be written (no space left, permission denied); the message names the file."""


class IncompleteOutputError(OutputError):
    """An output set on disk is incomplete or mixed: a file is missing or belongs to another build.

    ``problems``: every problem found, one sentence each (the message joins them with "; ").
    """

    def __init__(self, *problems: str) -> None:
        super().__init__("; ".join(problems))
        self.problems: tuple[str, ...] = problems


class MissingExtraError(TorusCadError):
    """An optional dependency is not installed; the message names the extra and the line that installs it
    (see :mod:`torus_cad.runtime.extras`)."""
