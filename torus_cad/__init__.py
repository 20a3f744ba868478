"""torus_cad: parametric toroidal propellers as OpenCascade solids, STEP and STL.

Two layers: :mod:`torus_cad.geometry` evaluates the spec exactly with numpy / scipy / geomdl;
:mod:`torus_cad.kernel` turns its arrays into cadquery / OCP shapes and files. The parameters
(:mod:`torus_cad.parameters`) are one validated schema; the pipeline that joins the layers is
:func:`build_propeller`.
"""

from typing import Any

from torus_cad.errors import GeometryError, KernelError, ParameterError, TorusCadError
from torus_cad.parameters import PropellerParameters, resolve_parameters

__version__ = "0.2.0"

__all__ = ["GeometryError", "KernelError", "ParameterError", "Propeller", "PropellerParameters", "TorusCadError",
           "build_propeller", "propeller_objects", "resolve_parameters"]

# The kernel (cadquery / OCP) loads only when one of these is asked for, so the geometry layer stays light.
_LAZY = {"build_propeller", "Propeller", "propeller_objects"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib
        return getattr(importlib.import_module("torus_cad.propeller"), name)
    raise AttributeError(f"module 'torus_cad' has no attribute {name!r}")
