"""The propeller as CadQuery objects, for people who continue in CadQuery.

::

    import cadquery as cq
    from torus_cad.cadquery_api import propeller_objects

    prop = propeller_objects("design.toml", overrides={"blades": 4, "hub.radius": 12.0})
    part = prop.workplane.faces(">Z").workplane().hole(5.0)   # a 5 mm bore through the hub
    prop.solid                      # the fused propeller, one valid cq.Solid (mm)
    prop.hub, prop.blades           # the hub cylinder and each blade on their own
    prop.assembly()                 # a cq.Assembly: "hub", "blade_0", ... with colours
    prop.mass_properties(1.24)      # volume, area, centroid, spin-axis inertia, mass (PLA)

All lengths are in millimetres, angles in degrees; the spin axis is the z axis and the hub is
centred at the origin (it spans z in [-L/2, L/2]).
"""

from __future__ import annotations

import colorsys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import cadquery as cq

from torus_cad.geometry.parameters import PropellerParameters, resolve_parameters
from torus_cad.kernel.checks import MassProperties, mass_properties
from torus_cad.propeller import DEFAULT_DENSITY_G_CM3, Propeller, build_propeller

#: Colour of the hub in assemblies and previews (RGB, 0..1).
HUB_COLOR: tuple[float, float, float] = (0.62, 0.64, 0.68)

_BLADE_PALETTE: tuple[tuple[float, float, float], ...] = (
    (0.12, 0.47, 0.71),  # blue
    (0.95, 0.50, 0.09),  # orange
    (0.17, 0.63, 0.17),  # green
    (0.84, 0.15, 0.16),  # red
    (0.58, 0.40, 0.74),  # purple
    (0.09, 0.75, 0.81),  # cyan
    (0.89, 0.47, 0.76),  # pink
    (0.74, 0.74, 0.13),  # olive
)


def blade_color(index: int, blades: int) -> tuple[float, float, float]:
    """A distinct RGB colour (0..1) for blade ``index`` of ``blades``; neighbours always differ."""
    if blades <= len(_BLADE_PALETTE):
        return _BLADE_PALETTE[index]
    hue = (0.58 + index / blades) % 1.0  # evenly spaced hues, starting at blue
    return colorsys.hsv_to_rgb(hue, 0.75, 0.85 if index % 2 == 0 else 0.70)


@dataclass(frozen=True)
class PropellerObjects:
    """A built propeller as CadQuery objects (millimetres; spin axis = z).

    Attributes:
        parameters: the design that was built.
        workplane: a ``cq.Workplane`` on XY holding the fused solid; chain CadQuery operations on it.
        solid: the fused propeller: one valid, closed ``cq.Solid``.
        hub: the hub cylinder alone (radius R, length L, centred at the origin), before the fuse.
        blades: each blade alone, before the fuse, blade i at ``phase_deg + 360 i / n`` degrees.
            The blades' ends reach into the hub, so hub and blades overlap; use ``solid`` for
            the union.
        propeller: the pipeline's full result (section data, stage times, ``write()``).
    """

    parameters: PropellerParameters
    workplane: cq.Workplane
    solid: cq.Solid
    hub: cq.Solid
    blades: list[cq.Solid]
    propeller: Propeller

    def assembly(self, name: str | None = None, fused: bool = False) -> cq.Assembly:
        """A ``cq.Assembly`` of named, coloured parts: ``hub`` and ``blade_0`` .. ``blade_{n-1}``.

        With ``fused=True`` it holds the single fused solid instead, named ``propeller``.
        The assembly's name defaults to the design's name.
        """
        assembly = cq.Assembly(name=name or self.parameters.name)
        if fused:
            assembly.add(self.solid, name="propeller", color=cq.Color(*HUB_COLOR))
            return assembly
        assembly.add(self.hub, name="hub", color=cq.Color(*HUB_COLOR))
        for index, blade in enumerate(self.blades):
            assembly.add(blade, name=f"blade_{index}", color=cq.Color(*blade_color(index, len(self.blades))))
        return assembly

    def mass_properties(self, density_g_cm3: float = DEFAULT_DENSITY_G_CM3) -> MassProperties:
        """Volume (mm^3), surface area (mm^2), centroid (mm), inertia about z (mm^5 and g mm^2)
        and mass (g) of the fused solid for a density in g/cm^3 (default 1.24, PLA), by OpenCascade."""
        return mass_properties(self.solid, density_g_cm3)

    def write(self, out_dir: str | Path, density_g_cm3: float = DEFAULT_DENSITY_G_CM3,
              stl: bool = True) -> dict[str, Path]:
        """Write ``<name>.step``, ``<name>.stl`` (unless ``stl`` is False) and ``<name>.json`` into ``out_dir``."""
        return self.propeller.write(out_dir, density_g_cm3, stl)


def propeller_objects(design: PropellerParameters | str | Path | None = None,
                      overrides: Mapping[str, Any] | None = None,
                      progress: Callable[[str], None] | None = None) -> PropellerObjects:
    """Build a propeller and return it as CadQuery objects.

    Args:
        design: a :class:`PropellerParameters`, the path of a TOML design file, or None for
            the default propeller.
        overrides: optional dotted-key changes applied on top of ``design``, in the design's
            units (mm, degrees), e.g. ``{"blades": 4, "hub.radius": 12.0}``.
        progress: optional callback, called with each pipeline stage's name as it starts.

    Returns:
        :class:`PropellerObjects` with the fused ``workplane`` / ``solid`` and the ``hub`` and
        ``blades`` on their own (all in mm, spin axis z).

    Raises:
        ParameterError: a bad parameter or design file (the message names the field).
        GeometryError: valid parameters that describe no sound propeller.
        KernelError: OpenCascade failed.
    """
    params = resolve_parameters(design, overrides)
    propeller = build_propeller(params, progress=progress)
    return PropellerObjects(parameters=params, workplane=propeller.workplane(), solid=propeller.solid,
                            hub=propeller.hub, blades=list(propeller.blades), propeller=propeller)


#: Another name for :func:`propeller_objects`.
cadquery_propeller = propeller_objects
