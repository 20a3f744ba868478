"""torus_cad: parametric toroidal propellers as OpenCascade solids, STEP and STL.

Two layers: :mod:`torus_cad.geometry` evaluates the spec exactly with numpy / scipy / geomdl;
:mod:`torus_cad.kernel` turns its arrays into cadquery / OCP shapes and files. The pipeline
that joins them is :func:`build_propeller`.
"""

from torus_cad.errors import GeometryError, KernelError, ParameterError, TorusCadError

__all__ = ["GeometryError", "KernelError", "ParameterError", "Propeller", "PropellerObjects",
           "PropellerParameters", "TorusCadError", "build_propeller", "propeller_objects"]

# The kernel (cadquery / OCP) loads only when one of these is asked for, so the geometry layer stays light.
# PropellerParameters too: the command line installs its signal handlers before numpy loads.
_LAZY = {"PropellerParameters": "torus_cad.geometry.parameters", "build_propeller": "torus_cad.propeller", "Propeller": "torus_cad.propeller",
         "propeller_objects": "torus_cad.cadquery_api", "PropellerObjects": "torus_cad.cadquery_api"}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'torus_cad' has no attribute {name!r}")
