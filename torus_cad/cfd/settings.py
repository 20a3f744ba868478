"""What ``torus-cad cfd`` needs beyond the ``[cfd]`` table (``torus_cad.parameters.design.Cfd``)."""

from __future__ import annotations

from torus_cad.errors import MissingExtraError
from torus_cad.parameters.design import Cfd, InletSide

__all__ = ["Cfd", "InletSide", "MissingExtraError"]
