"""The package's exceptions: one base, one subclass per kind of failure.

The CLI maps :class:`ParameterError` to exit code 2 (bad input) and every other
:class:`TorusCadError` to exit code 1 (the kernel or the file system failed).
"""


class TorusCadError(Exception):
    """Base of every error torus_cad raises on purpose."""


class ParameterError(TorusCadError, ValueError):
    """A design parameter or configuration file is invalid; the message names the field."""


class GeometryError(TorusCadError):
    """The parameters are valid one by one but describe no sound propeller (e.g. a Frenet frame is undefined)."""


class KernelError(TorusCadError):
    """OpenCascade failed to build, check or export the solid."""
