"""The design parameters: one pydantic schema, each parameter declared once (:mod:`.design`).

::

    from torus_cad.parameters import PropellerParameters, resolve_parameters
    params = resolve_parameters("design.toml", {"blades": 4})
    params.hub.radius       # mm

The schema only: the geometry the parameters describe is :mod:`torus_cad.design`'s.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from torus_cad.parameters.design import PropellerParameters, StepSchema
from torus_cad.parameters.schema import ParameterSpec, iter_parameter_specs

__all__ = [
    "ParameterSpec",
    "PropellerParameters",
    "StepSchema",
    "parameter_specs",
    "resolve_parameters",
]


def parameter_specs() -> list[ParameterSpec]:
    """Every parameter of a propeller design, in declaration order."""
    return list(iter_parameter_specs(PropellerParameters))


def resolve_parameters(
    design: PropellerParameters | str | Path | None = None,
    overrides: Mapping[str, Any] | None = None,
) -> PropellerParameters:
    """The parameters of ``design`` (parameters, a TOML path, or None for the default) with
    dotted-key ``overrides`` applied, e.g. ``{"blades": 4, "hub.radius": 12.0}`` (validated)."""
    if design is None:
        params = PropellerParameters()
    elif isinstance(design, PropellerParameters):
        params = design
    else:
        params = PropellerParameters.from_toml(design)
    return params.with_values(dict(overrides)) if overrides else params
