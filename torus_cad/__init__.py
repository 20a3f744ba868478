"""torus_cad: parametric toroidal propellers as OpenCascade solids, STEP and STL.

Two layers: :mod:`torus_cad.geometry` evaluates the spec exactly with numpy / scipy / geomdl;
:mod:`torus_cad.kernel` turns its arrays into cadquery / OCP shapes and files. The pipeline
that joins them is :func:`build_propeller`.
"""

from torus_cad.errors import GeometryError, KernelError, ParameterError, TorusCadError
from torus_cad.geometry.parameters import PropellerParameters

__all__ = ["GeometryError", "KernelError", "ParameterError", "PropellerParameters", "Propeller",
           "TorusCadError", "build_propeller"]


def __getattr__(name: str):
    # The kernel (cadquery / OCP) loads only when asked for, so the geometry layer stays light.
    if name in ("build_propeller", "Propeller"):
        from torus_cad import propeller
        return getattr(propeller, name)
    raise AttributeError(f"module 'torus_cad' has no attribute {name!r}")
