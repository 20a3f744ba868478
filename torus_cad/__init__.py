"""torus_cad: parametric toroidal propellers as OpenCascade solids, STEP and STL.

Two layers: :mod:`torus_cad.geometry` evaluates the spec exactly with numpy / scipy / geomdl;
:mod:`torus_cad.kernel` turns its arrays into cadquery / OCP shapes and files. The parameters
(:mod:`torus_cad.parameters`) are one validated schema; the pipeline that joins the layers is
:func:`build_propeller`.
"""

from typing import Any

from torus_cad.errors import GeometryError, KernelError, ParameterError, TorusCadError

__version__ = "0.2.1"

__all__ = [
    "GeometryError",
    "KernelError",
    "ParameterError",
    "Propeller",
    "PropellerParameters",
    "TorusCadError",
    "build_propeller",
    "propeller_objects",
    "resolve_parameters",
]

# Each loads when first asked for: the kernel (cadquery / OCP) takes seconds, the schema (pydantic,
# scipy through the geometry) most of a second, and `torus-cad build` shows its first line before
# either.
_LAZY = {
    "build_propeller": "torus_cad.propeller",
    "Propeller": "torus_cad.propeller",
    "propeller_objects": "torus_cad.propeller",
    "PropellerParameters": "torus_cad.parameters",
    "resolve_parameters": "torus_cad.parameters",
}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'torus_cad' has no attribute {name!r}")
