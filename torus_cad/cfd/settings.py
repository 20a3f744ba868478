"""What ``torus-cad cfd`` needs beyond the ``[cfd]`` table (``torus_cad.parameters.design.Cfd``)."""

from __future__ import annotations

from torus_cad.errors import TorusCadError
from torus_cad.parameters.design import Cfd, InletSide


class MissingExtraError(TorusCadError):
    """An optional dependency is not installed; the message names the extra that installs it."""


__all__ = ["Cfd", "InletSide", "MissingExtraError"]
