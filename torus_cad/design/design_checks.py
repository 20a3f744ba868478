"""A design's feasibility before the kernel: every refusal of the build that needs no OpenCascade.

:func:`check_design` runs, in the order :func:`torus_cad.propeller.build_propeller` runs them,
every check that can refuse a design before the kernel builds anything: the parameters and
their cross-field rules, the design targets (``diameter``, ``pitch``), blade 0's sampled
surface, the geometric checks (:mod:`torus_cad.geometry.analysis.feasibility`: the ends
inside the hub's inset, the centerline leaving through the hub's side, the trailing edge, no
fold-over inside a bend, sections dense enough, no self-intersection, blades clear of each
other; for a conventional blade
:func:`~torus_cad.geometry.blade.conventional_blade.check_conventional_feasible`), the hub's
mounting features against the blades (:mod:`torus_cad.geometry.hub.mounting`), the section fit and
its trailing edge (:mod:`torus_cad.geometry.section.section_fit`) and, when the design writes a
mesh, the STL's triangle budget. The blade's walls against ``manufacturing.min_wall``
(:mod:`torus_cad.geometry.analysis.printability`) are measured too; they refuse the design only when
asked (``--require-printable``), as in the build.

Nothing here imports the kernel (numpy, scipy and the geometry layer only), so ``torus-cad
check`` answers without loading OpenCascade, and sweeps and studies refuse such designs in
their own process before a worker builds them (:func:`torus_cad.batch.job.prescreen`). The
first refusal raises the same ParameterError or GeometryError, with the same line, that the
build would raise.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from torus_cad.design.described_geometry import wall_printability
from torus_cad.design.prepared_design import prepare_design
from torus_cad.design.stl_budget import check_stl_budget
from torus_cad.errors import GeometryError
from torus_cad.geometry.analysis.feasibility import FOLD_LIMIT, RESOLUTION_DEVIATION_LIMIT, Margins
from torus_cad.geometry.analysis.printability import Printability
from torus_cad.geometry.blade.blade_surface import BladeSurface
from torus_cad.parameters.design import PropellerParameters, TrailingEdgeShape

__all__ = ["Feasibility", "check_design"]

#: What check cannot say without the kernel (a knife edge's fillet is refused before it:
#: torus_cad.geometry.analysis.feasibility.check_root_fillet_edge): round a flat blunt edge the
#: fillet's ball is stopped by the base's corners at one radius and not at a smaller one (the
#: default with a 0.4 mm flat edge: 0.5 mm fails, 0.25 mm builds), which only OpenCascade's fillet
#: finds. Round a round blunt edge the fillet's ball may still not fit a thin root or a tight bend
#: (the APC 10x7 SF's 0.9 mm root takes 0.05 mm).
EDGE_FILLET_NOTE = (
    "the root fillet round a {edge} trailing edge is "
    "decided by the kernel (build): OpenCascade's fillet "
    "{why} on some designs and radii; a round blunt edge (airfoil.trailing_edge_thickness > 0, "
    "airfoil.trailing_edge_shape = 'round') is the one it rolls round"
)
ROUND_EDGE_FILLET_NOTE = (
    "the root fillet is made by the kernel (build): whether OpenCascade's rolling ball fits the "
    "blade roots (a thin root, a tight bend) is known only when the build makes it; the build "
    "names a radius that fits if this one does not"
)


@dataclass(frozen=True)
class Feasibility:
    """A design that passed every check before the kernel, and how close it came (mm).

    Attributes:
        parameters: the spec parameters the design resolved to (design targets applied).
        surface: blade 0's sampled surface at ``resolution``.
        margins: the largest fold ratio and section sag (toroidal designs; None for a conventional
            one).
        printability: the blade's thinnest wall and trailing edge against ``manufacturing.min_wall``
            (None unless asked for: the analytic walls take longer than the checks).
        stl_triangles: the STL's estimated triangles (None when the design writes no mesh).
        cpu_seconds: CPU time of the checks in this process, s (what they cost, however busy the
            machine).
    """

    parameters: PropellerParameters
    surface: BladeSurface
    margins: Margins | None
    printability: Printability | None
    stl_triangles: int | None
    cpu_seconds: float

    @property
    def tip_diameter_mm(self) -> float:
        """Twice the largest distance of the sampled blade surface from the spin axis, mm."""
        return 2.0 * float(np.hypot(self.surface.points[..., 0], self.surface.points[..., 1]).max())

    @property
    def undecided(self) -> list[str]:
        """What only the kernel can decide about this design (one line each; empty for most
        designs)."""
        params = self.parameters
        if params.hub.root_fillet_radius == 0.0:
            return []
        if params.airfoil.trailing_edge_shape == TrailingEdgeShape.FLAT:
            return [EDGE_FILLET_NOTE.format(edge="flat", why="is stopped by the base's corners")]
        return [ROUND_EDGE_FILLET_NOTE]

    def summary(self) -> str:
        """One line: the design, its size, the margins to the limits, its walls and the check's
        time."""
        params = self.parameters
        parts = [
            f"feasible: {params.name}, {params.blades} blade{'s' if params.blades > 1 else ''}, "
            f"tip diameter {self.tip_diameter_mm:.1f} mm"
        ]
        if self.margins is not None:
            parts.append(
                f"fold ratio {self.margins.fold_ratio:.2f} (limit {FOLD_LIMIT:g}), section sag "
                f"{self.margins.resolution_deviation:.1%} of the "
                f"chord (limit {RESOLUTION_DEVIATION_LIMIT:.0%})"
            )
        if self.stl_triangles is not None:
            parts.append(f"about {self.stl_triangles:,} STL triangles")
        wall = self.printability
        if wall is not None:
            parts.append(
                f"walls: thinnest {wall.thinnest_wall_mm:.2f} mm, "
                f"trailing edge {wall.trailing_edge_thickness_mm:.2f} "
                f"mm (manufacturing.min_wall {wall.min_wall_mm:g} mm"
                + ("" if wall.printable else ": not printable")
                + ")"
            )
        return "; ".join(parts) + f"; checked without the kernel in {self.cpu_seconds:.2f} s of CPU"


def check_design(
    params: PropellerParameters,
    *,
    mesh: bool = False,
    walls: bool = False,
    require_printable: bool = False,
    estimate_mesh_first: bool = False,
) -> Feasibility:
    """Every check the build makes before the kernel, in its order; the first refusal raises.

    Args:
        params: the design as read (its design targets are resolved here, as the build does).
        mesh: the design writes a mesh (STL or 3MF): its triangle budget is checked on the fitted
            section curves, as the write does.
        walls: measure the blade's walls (:attr:`Feasibility.printability`).
        require_printable: refuse a blade thinner than ``manufacturing.min_wall``
            (``--require-printable``), first, as the build command does.
        estimate_mesh_first: with ``mesh``, also check the budget before the geometry, from the
            usual pole grid, as the build command does before it builds (a batch's build checks it
            only when it writes).

    Raises:
        ParameterError: a rule between fields, a design target that cannot be met, a mesh over its
            budget.
        GeometryError: valid parameters that describe no sound propeller (the line names the check).
    """
    start = time.process_time()
    # first, as the build command
    printability = wall_printability(params) if require_printable else None
    if printability is not None and printability.problem():
        raise GeometryError(f"not printable (--require-printable): {printability.problem()}")
    if mesh and estimate_mesh_first:
        check_stl_budget(params)
    prepared = prepare_design(params)
    params, surface = prepared.parameters, prepared.surface
    triangles = None
    if mesh:
        triangles = check_stl_budget(params, surface, prepared.fit.poles.shape[:2])
    if walls and printability is None:
        printability = wall_printability(params)
    return Feasibility(
        params, surface, prepared.margins, printability, triangles, time.process_time() - start
    )
