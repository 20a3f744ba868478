"""The file formats a build writes and their variants: choices that the parameters, the writers and
the report carry as the same enums (kernel-free, so every layer may import it)."""

from __future__ import annotations

from enum import StrEnum


class ExportFormat(StrEnum):
    """A file format the build writes."""

    STEP = "step"
    STL = "stl"
    THREE_MF = "3mf"


class StepSchema(StrEnum):
    """The STEP application protocol written."""

    AP214 = "AP214"
    AP242 = "AP242"
