"""Mass properties computed by OpenCascade: volume, area, centre of mass, inertia, mass and the
balance about the axis, each by adaptive integration (BRepGProp) to a stated relative precision."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from OCP.Bnd import Bnd_Box
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepGProp import BRepGProp
from OCP.gp import gp_Ax1, gp_Dir, gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.TopoDS import TopoDS_Shape

from torus_cad.kernel.blade_integrals import hub_with_blade_integrals
from torus_cad.kernel.topology import AnyShape, occ
from torus_cad.tolerances import BALANCE_RELATIVE_PRECISION

#: Relative precision of OpenCascade's adaptive volume / inertia integration (BRepGProp eps).
#: cadquery's Shape.Volume() integrates without it and is off by ~2 % on lofted blades.
MASS_PROPERTIES_RELATIVE_PRECISION = 1e-6

#: The last (shape, relative precision, answer) of :func:`volume_properties`.
_LAST_VOLUME: list[tuple[TopoDS_Shape | None, float, GProp_GProps | None]] = [(None, 0.0, None)]


@dataclass(frozen=True)
class MassProperties:
    """Mass properties of a solid, to 1e-6 relative or better.

    Attributes:
        volume_mm3: volume, mm^3.
        surface_area_mm2: area of the boundary, mm^2.
        centroid_mm: (x, y, z) centre of volume, mm.
        spin_axis_inertia_mm5: integral of r^2 dV about the z axis (the spin axis), mm^5.
        density_g_cm3: density used for the mass, g/cm^3.
        mass_g: mass, g.
        spin_axis_inertia_g_mm2: moment of inertia about the z axis, g mm^2.
        bounding_box_mm: ((xmin, ymin, zmin), (xmax, ymax, zmax)), tight box, mm.
    """

    volume_mm3: float
    surface_area_mm2: float
    centroid_mm: tuple[float, float, float]
    spin_axis_inertia_mm5: float
    density_g_cm3: float
    mass_g: float
    spin_axis_inertia_g_mm2: float
    bounding_box_mm: tuple[tuple[float, float, float], tuple[float, float, float]]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


def volume_properties(
    shape: AnyShape, relative_precision: float = MASS_PROPERTIES_RELATIVE_PRECISION
) -> GProp_GProps:
    """OpenCascade volume properties by adaptive integration (not cadquery's coarse default). The
    last shape's answer is kept and given again for a request no more precise: the JSON report asks
    for the mass properties (1e-6) and then the balance (1e-4) of the same solid, seconds each on a
    bored hub."""
    solid = occ(shape)
    last_shape, last_precision, last_answer = _LAST_VOLUME[0]
    if (
        last_shape is not None
        and last_answer is not None
        and last_precision <= relative_precision
        and last_shape.IsEqual(solid)
    ):
        return last_answer
    properties = GProp_GProps()
    BRepGProp.VolumeProperties_s(solid, properties, relative_precision, False)
    _LAST_VOLUME[0] = (solid, relative_precision, properties)
    return properties


def precise_volume(
    shape: AnyShape, relative_precision: float = MASS_PROPERTIES_RELATIVE_PRECISION
) -> float:
    """Volume in mm^3 by adaptive integration to ``relative_precision``."""
    return float(volume_properties(shape, relative_precision).Mass())


def mass_properties(shape: AnyShape, density_g_cm3: float) -> MassProperties:
    """Volume, area, centroid, inertia about the z axis, mass and box of ``shape`` for a density in
    g/cm^3.

    A hub with blades (what the shared-intersection fuse makes) is integrated over its blade
    faces alone (:mod:`torus_cad.kernel.blade_integrals`, ~4e-10 relative, a fraction of the
    time); any other shape by OpenCascade's adaptive integration, :func:`occt_mass_properties`.
    """
    integrals = hub_with_blade_integrals(occ(shape))
    if integrals is None:
        return occt_mass_properties(shape, density_g_cm3)
    return _with_density(
        integrals.volume_mm3,
        integrals.area_mm2,
        integrals.centroid_mm.tolist(),
        integrals.spin_inertia_mm5,
        density_g_cm3,
        (integrals.box_min_mm.tolist(), integrals.box_max_mm.tolist()),
    )


def occt_mass_properties(
    shape: AnyShape,
    density_g_cm3: float,
    relative_precision: float = MASS_PROPERTIES_RELATIVE_PRECISION,
) -> MassProperties:
    """:func:`mass_properties` of any shape by OpenCascade: BRepGProp's adaptive integration to
    ``relative_precision`` and BRepBndLib's optimal box (which adds 1e-7 mm on every side)."""
    volume = volume_properties(shape, relative_precision)
    centre = volume.CentreOfMass()
    box = Bnd_Box()
    BRepBndLib.AddOptimal_s(occ(shape), box, False, False)
    xmin, ymin, zmin, xmax, ymax, zmax = box.Get()
    area = surface_area_mm2(shape, relative_precision)
    return _with_density(
        float(volume.Mass()),
        area,
        (centre.X(), centre.Y(), centre.Z()),
        float(volume.MomentOfInertia(gp_Ax1(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)))),
        density_g_cm3,
        ((xmin, ymin, zmin), (xmax, ymax, zmax)),
    )


def surface_area_mm2(shape: AnyShape, relative_precision: float | None = None) -> float:
    """The area of ``shape``'s faces, mm^2: BRepGProp's adaptive integration to
    ``relative_precision``, or with None its fixed Gauss rule (enough for an estimate, and
    faster)."""
    surface = GProp_GProps()
    if relative_precision is None:
        BRepGProp.SurfaceProperties_s(occ(shape), surface)
    else:
        BRepGProp.SurfaceProperties_s(occ(shape), surface, relative_precision, False)
    return float(surface.Mass())


def _with_density(
    volume_mm3: float,
    area_mm2: float,
    centroid_mm: Sequence[float],
    inertia_mm5: float,
    density_g_cm3: float,
    box_mm: Sequence[Sequence[float]],
) -> MassProperties:
    density_g_mm3 = density_g_cm3 * 1e-3
    (x, y, z), ((x_min, y_min, z_min), (x_max, y_max, z_max)) = (
        (float(value) for value in centroid_mm),
        box_mm,
    )
    return MassProperties(
        volume_mm3=float(volume_mm3),
        surface_area_mm2=float(area_mm2),
        centroid_mm=(x, y, z),
        spin_axis_inertia_mm5=float(inertia_mm5),
        density_g_cm3=density_g_cm3,
        mass_g=float(volume_mm3) * density_g_mm3,
        spin_axis_inertia_g_mm2=float(inertia_mm5) * density_g_mm3,
        bounding_box_mm=(
            (float(x_min), float(y_min), float(z_min)),
            (float(x_max), float(y_max), float(z_max)),
        ),
    )


@dataclass(frozen=True)
class Balance:
    """How far a part is from spinning true about the z axis.

    Attributes:
        static_imbalance_g_mm: mass times the distance of the centroid from the spin axis, g mm.
        centroid_offset_mm: that distance, mm.
        products_of_inertia_g_mm2: {"xz", "yz", "xy"}: integrals of (x - cx)(z - cz) dm, ... about
            axes through the centroid parallel to x, y, z, g mm^2. xz and yz are the couple
            (dynamic) imbalance about the spin axis; 0 for a part symmetric about it.
    """

    static_imbalance_g_mm: float
    centroid_offset_mm: float
    products_of_inertia_g_mm2: dict[str, float]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict."""
        return asdict(self)


def balance_of(properties: GProp_GProps, density_g_cm3: float) -> Balance:
    """:class:`Balance` from OpenCascade's volume properties and a density in g/cm^3."""
    density_g_mm3 = density_g_cm3 * 1e-3
    centre = properties.CentreOfMass()
    offset = float(np.hypot(centre.X(), centre.Y()))
    # about the centroid; off-diagonal terms are minus the products
    matrix = properties.MatrixOfInertia()
    products = {
        name: -float(matrix.Value(row, column)) * density_g_mm3
        for name, (row, column) in (("xz", (1, 3)), ("yz", (2, 3)), ("xy", (1, 2)))
    }
    return Balance(float(properties.Mass()) * density_g_mm3 * offset, offset, products)


def balance(
    shape: AnyShape, density_g_cm3: float, relative_precision: float = BALANCE_RELATIVE_PRECISION
) -> Balance:
    """Static imbalance and products of inertia of ``shape``: from the blade faces alone for a hub
    with blades (as :func:`mass_properties`), else by OpenCascade's adaptive integration to
    ``relative_precision``."""
    integrals = hub_with_blade_integrals(occ(shape))
    if integrals is None:
        return balance_of(volume_properties(shape, relative_precision), density_g_cm3)
    density_g_mm3 = density_g_cm3 * 1e-3
    (cx, cy, cz), volume = integrals.centroid_mm, integrals.volume_mm3
    # parallel axes
    about_centroid = integrals.products_mm5 - volume * np.array([cx * cz, cy * cz, cx * cy])
    offset = float(np.hypot(cx, cy))
    products = {
        name: float(value) * density_g_mm3
        for name, value in zip(("xz", "yz", "xy"), about_centroid, strict=True)
    }
    return Balance(volume * density_g_mm3 * offset, offset, products)
