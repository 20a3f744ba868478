"""Boundary-layer meshes of a propeller's closed surface with OpenFOAM's snappyHexMesh.

The input is what any propeller has, whatever made it: a closed triangulated surface (STL, mm), its
tip diameter, and its spin axis (+z through the origin). No toroidal parameter is read, so a
conventional propeller or a user's own STEP (triangulated) goes through the same route.

The case gets (all lengths in metres inside the case):

* ``constant/triSurface/propeller.stl``: the surface scaled from mm (``surfaceTransformPoints``);
* ``system/blockMeshDict``: a background box of cubes of edge ``D / BACKGROUND_CELLS_PER_D``
  (divided by the level's scale), its ends the ``inlet`` and ``outlet``, its four sides the
  ``farfield``;
* ``system/surfaceFeatureExtractDict``: the surface's sharp edges (leading and trailing edges, hub
  rims);
* ``system/snappyHexMeshDict``: the propeller refined to ``SURFACE_LEVEL`` (its edges to
  ``FEATURE_LEVEL``), a ``searchableCylinder`` around it made the MRF ``cellZone`` / ``faceZone``
  ``rotating_zone`` (snapped to the cylinder, refined to ``ZONE_LEVEL``), and ``LAYERS`` prism
  layers on the propeller whose first-cell height comes from a y+ target
  (:func:`first_cell_height_m`);
* ``checkMesh``, whose verdict and cell-type counts :func:`parse_check_mesh` reads.

Levels divide every length of the mesh (background cells, hence every refinement level, and the
layers' first-cell height) by ``REFINEMENT_RATIO`` per step; the layer count and expansion ratio
stay the same, so the three levels are geometrically similar.
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from foamlib import FoamFile

from torus_cad.errors import ParameterError
from torus_cad.simulate.settings import (
    AIR_15C,
    BACKGROUND_CELLS_PER_D,
    FEATURE_LEVEL,
    LAST_LAYER_MIN_FRACTION,
    LAYER_EXPANSION_RATIO,
    LAYER_STACK_MAX_SURFACE_CELLS,
    LAYERS,
    REFINEMENT_RATIO,
    SURFACE_LEVEL,
    Y_PLUS_REFERENCE_RADIUS,
    Y_PLUS_TARGET,
    ZONE_LEVEL,
    Fluid,
    Level,
)

WALL, ZONE = "propeller", "rotating_zone"
MM_TO_M = 1e-3
#: Names of the case files this module writes.
SURFACE_MM = "constant/triSurface/propeller_mm.stl"
SURFACE_M = "constant/triSurface/propeller.stl"
#: The commands that make the mesh from the dictionaries, in the case folder.
MESH_COMMANDS: tuple[tuple[str, ...], ...] = (
    ("blockMesh",),
    ("surfaceTransformPoints", "-scale", "(0.001 0.001 0.001)", SURFACE_MM, SURFACE_M),
    ("surfaceFeatureExtract",),
    ("snappyHexMesh", "-overwrite"),
    ("checkMesh",),
)


@dataclass(frozen=True)
class Domain:
    """The fluid domain in metres, around a propeller on +z: the box's half width, the inlet's and
    outlet's z, the rotating zone (cylinder radius and z range)."""

    half_width_m: float
    inlet_z_m: float
    outlet_z_m: float
    zone_radius_m: float
    zone_z_m: tuple[float, float]


def skin_friction(reynolds: float) -> float:
    """Local skin-friction coefficient of a turbulent flat plate at ``reynolds`` (White: 0.026
    Re_x^-1/7).

    Used at any Reynolds number: at the blades' Re of a few thousand the laminar 0.664 Re_x^-1/2 is
    about 20 % higher (a cell about 8 % thinner); the y+ measured on the default design's coarse
    mesh (mean 1.13 for a target of 1) shows the estimate is close enough."""
    return 0.026 * reynolds ** (-1.0 / 7.0)


#: The length the blade's Reynolds number is taken over at ``Y_PLUS_REFERENCE_RADIUS``, in tip
#: diameters: a typical chord there (the default design's 6.0 mm is 0.133 D, the APC's about 0.11
#: D).
REFERENCE_CHORD_D = 0.1


def reference_speed_m_s(diameter_m: float, rpm: float, airspeed_m_s: float) -> float:
    """The speed (m/s) the blade meets at r = ``Y_PLUS_REFERENCE_RADIUS`` x R: sqrt((omega r)^2 +
    airspeed^2)."""
    omega = rpm * 2.0 * math.pi / 60.0
    return math.hypot(omega * Y_PLUS_REFERENCE_RADIUS * diameter_m / 2.0, airspeed_m_s)


def reference_reynolds(
    diameter_m: float, rpm: float, airspeed_m_s: float, fluid: Fluid = AIR_15C
) -> float:
    """The blade's Reynolds number at r = ``Y_PLUS_REFERENCE_RADIUS`` x R over ``REFERENCE_CHORD_D``
    x D (dimensionless): :func:`reference_speed_m_s` times that chord over the fluid's viscosity."""
    return (
        reference_speed_m_s(diameter_m, rpm, airspeed_m_s)
        * REFERENCE_CHORD_D
        * diameter_m
        / fluid.viscosity_m2_s
    )


def first_cell_height_m(
    diameter_m: float,
    rpm: float,
    airspeed_m_s: float,
    y_plus: float = Y_PLUS_TARGET,
    fluid: Fluid = AIR_15C,
    reference_length_m: float | None = None,
) -> float:
    """Height of the first prism layer on the propeller, in m, for a wall y+ of ``y_plus``.

    Flat-plate estimate at the blade's reference station r = ``Y_PLUS_REFERENCE_RADIUS`` x R: speed
    V = sqrt((omega r)^2 + airspeed^2) (m/s), Reynolds number V L / nu with L =
    ``reference_length_m`` (default ``REFERENCE_CHORD_D`` x D, a typical chord there), u_tau = V
    sqrt(Cf / 2), height = y+ nu / u_tau. At 0 rpm and no airspeed the tip speed of 1000 rpm stands
    in (a still propeller still gets a layer)."""
    speed = reference_speed_m_s(
        diameter_m, max(rpm, 1000.0 if airspeed_m_s == 0.0 else 0.0), airspeed_m_s
    )
    length = (
        reference_length_m if reference_length_m is not None else REFERENCE_CHORD_D * diameter_m
    )
    reynolds = speed * length / fluid.viscosity_m2_s
    u_tau = speed * math.sqrt(skin_friction(reynolds) / 2.0)
    return y_plus * fluid.viscosity_m2_s / u_tau


def level_scale(level: Level) -> float:
    """Lengths of ``level`` are the coarse level's divided by this (REFINEMENT_RATIO per step)."""
    return float(REFINEMENT_RATIO ** list(Level).index(level))


def read_stl_points_mm(path: Path) -> np.ndarray:
    """The vertices (n, 3) of a binary or ASCII STL, in its own units."""
    data = path.read_bytes()
    if len(data) >= 84:
        count = struct.unpack_from("<I", data, 80)[0]
        if len(data) == 84 + 50 * count:
            record = np.dtype(
                [("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")]
            )
            return (
                np.frombuffer(data, dtype=record, offset=84, count=count)["vertices"]
                .reshape(-1, 3)
                .astype(float)
            )
    numbers = re.findall(rb"vertex\s+(\S+)\s+(\S+)\s+(\S+)", data)
    return np.array(numbers, dtype=float).reshape(-1, 3)


def domain_around(
    points_mm: np.ndarray,
    diameter_mm: float,
    flow_sign: float,
    domain_d: dict[str, float],
    zone_radius_d: float,
    zone_clearance_d: float,
) -> Domain:
    """The box and the rotating zone (m) around a propeller whose surface has ``points_mm``.

    ``flow_sign`` is -1 when the flow goes toward -z (inlet at +z). ``domain_d`` holds
    ``domain_radius`` (the box's half width), ``upstream`` and ``downstream`` in D."""
    d = diameter_mm * MM_TO_M
    z_low, z_high = (float(v) * MM_TO_M for v in (points_mm[:, 2].min(), points_mm[:, 2].max()))
    up, down = domain_d["upstream"] * d, domain_d["downstream"] * d
    inlet, outlet = (up, -down) if flow_sign < 0 else (-up, down)
    clearance = zone_clearance_d * d
    return Domain(
        domain_d["domain_radius"] * d,
        inlet,
        outlet,
        zone_radius_d * d,
        (z_low - clearance, z_high + clearance),
    )


def _write(path: Path, entries: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with FoamFile(path) as dictionary:
        for key, value in entries.items():
            dictionary[key] = value


def block_mesh_dict(domain: Domain, cell_m: float) -> dict[str, Any]:
    """A box of cubes of edge ``cell_m`` exactly (so the levels' cells keep the refinement ratio):
    the box reaches at least ``domain``'s half width and inlet, its outlet end as far as the whole
    cubes take it; patches inlet, outlet (the z ends) and farfield (the sides)."""
    n_xy = math.ceil(2.0 * domain.half_width_m / cell_m - 1e-9)
    w = 0.5 * n_xy * cell_m
    n_z = math.ceil(abs(domain.inlet_z_m - domain.outlet_z_m) / cell_m - 1e-9)
    outlet = domain.inlet_z_m + math.copysign(n_z * cell_m, domain.outlet_z_m - domain.inlet_z_m)
    z0, z1 = min(domain.inlet_z_m, outlet), max(domain.inlet_z_m, outlet)
    vertices = [
        [-w, -w, z0],
        [w, -w, z0],
        [w, w, z0],
        [-w, w, z0],
        [-w, -w, z1],
        [w, -w, z1],
        [w, w, z1],
        [-w, w, z1],
    ]
    low, high = [0, 3, 2, 1], [4, 5, 6, 7]
    ends = {
        "inlet": high if domain.inlet_z_m > outlet else low,
        "outlet": low if domain.inlet_z_m > outlet else high,
    }
    sides = [[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]]
    return {
        "scale": 1,
        "vertices": vertices,
        "blocks": ["hex", [0, 1, 2, 3, 4, 5, 6, 7], [n_xy, n_xy, n_z], "simpleGrading", [1, 1, 1]],
        "edges": [],
        "boundary": [
            ("inlet", {"type": "patch", "faces": [ends["inlet"]]}),
            ("outlet", {"type": "patch", "faces": [ends["outlet"]]}),
            ("farfield", {"type": "patch", "faces": sides}),
        ],
        "mergePatchPairs": [],
    }


def layer_stack_m(first_layer_m: float, layers: int) -> float:
    """Total height (m) of ``layers`` prism layers growing by ``LAYER_EXPANSION_RATIO`` from
    ``first_layer_m``."""
    return first_layer_m * (LAYER_EXPANSION_RATIO**layers - 1.0) / (LAYER_EXPANSION_RATIO - 1.0)


def layer_count(first_layer_m: float, surface_cell_m: float) -> int:
    """The prism layers asked of snappyHexMesh: ``LAYERS``, or the most (at least 1) whose stack is
    at most ``LAYER_STACK_MAX_SURFACE_CELLS`` surface cells (m), the first layer kept."""
    limit_m = LAYER_STACK_MAX_SURFACE_CELLS * surface_cell_m
    return next(
        (count for count in range(LAYERS, 0, -1) if layer_stack_m(first_layer_m, count) <= limit_m),
        1,
    )


def snappy_dict(
    domain: Domain, cell_m: float, first_layer_m: float, surface_refinement: int = 0
) -> dict[str, Any]:
    """snappyHexMeshDict: refinement, the rotating cellZone / faceZone, prism layers on the
    propeller; the propeller's surface and edges refined ``surface_refinement`` levels beyond
    ``SURFACE_LEVEL`` and
    ``FEATURE_LEVEL``."""
    surface_level, feature_level = (
        SURFACE_LEVEL + surface_refinement,
        FEATURE_LEVEL + surface_refinement,
    )
    layers = layer_count(first_layer_m, cell_m / 2.0**surface_level)
    point = [
        0.5 * (domain.zone_radius_m + domain.half_width_m) + 0.1234 * cell_m,
        0.0321 * cell_m,
        0.5 * sum(domain.zone_z_m) + 0.0213 * cell_m,
    ]
    zone_half = 0.5 * (domain.zone_z_m[1] - domain.zone_z_m[0])
    zone_mid = 0.5 * sum(domain.zone_z_m)
    return {
        "castellatedMesh": True,
        "snap": True,
        "addLayers": True,
        "geometry": {
            "propeller.stl": {"type": "triSurfaceMesh", "name": WALL},
            ZONE: {
                "type": "searchableCylinder",
                "point1": [0, 0, zone_mid - zone_half],
                "point2": [0, 0, zone_mid + zone_half],
                "radius": domain.zone_radius_m,
            },
        },
        "castellatedMeshControls": {
            "maxLocalCells": 2_000_000,
            "maxGlobalCells": 20_000_000,
            "minRefinementCells": 0,
            "maxLoadUnbalance": 0.1,
            "nCellsBetweenLevels": 2,
            "resolveFeatureAngle": 30,
            "allowFreeStandingZoneFaces": True,
            "features": [{"file": '"propeller.eMesh"', "level": feature_level}],
            "refinementSurfaces": {
                WALL: {"level": [surface_level, surface_level], "patchInfo": {"type": "wall"}},
                ZONE: {
                    "level": [ZONE_LEVEL, ZONE_LEVEL],
                    "faceZone": ZONE,
                    "cellZone": ZONE,
                    "cellZoneInside": "inside",
                },
            },
            "refinementRegions": {ZONE: {"mode": "inside", "levels": [[1e15, ZONE_LEVEL]]}},
            "locationInMesh": point,
        },
        "snapControls": {
            "nSmoothPatch": 3,
            "tolerance": 2.0,
            "nSolveIter": 100,
            "nRelaxIter": 5,
            "nFeatureSnapIter": 10,
            "implicitFeatureSnap": False,
            "explicitFeatureSnap": True,
            "multiRegionFeatureSnap": False,
        },
        "addLayersControls": {
            "relativeSizes": False,
            "layers": {WALL: {"nSurfaceLayers": layers}},
            "expansionRatio": LAYER_EXPANSION_RATIO,
            "firstLayerThickness": first_layer_m,
            "minThickness": 0.1 * first_layer_m,
            "nGrow": 0,
            "featureAngle": 60,
            "slipFeatureAngle": 30,
            "nRelaxIter": 5,
            "nSmoothSurfaceNormals": 1,
            "nSmoothNormals": 3,
            "nSmoothThickness": 10,
            "maxFaceThicknessRatio": 0.5,
            "maxThicknessToMedialRatio": 0.8,
            "minMedialAxisAngle": 130,
            "nBufferCellsNoExtrude": 0,
            "nLayerIter": 50,
            "nRelaxedIter": 20,
        },
        "meshQualityControls": {
            "maxNonOrtho": 65,
            "maxBoundarySkewness": 3.5,
            "maxInternalSkewness": 3.5,
            "maxConcave": 80,
            "minVol": 1e-18,
            "minTetQuality": -1e30,
            "minArea": -1,
            "minTwist": 0.01,
            "minDeterminant": 0.001,
            "minFaceWeight": 0.05,
            "minVolRatio": 0.01,
            "minTriangleTwist": -1,
            "nSmoothScale": 4,
            "errorReduction": 0.75,
            "relaxed": {
                "maxNonOrtho": 70,
                "minTetQuality": -1e30,
                "minTwist": 0.01,
                "minDeterminant": 1e-4,
                "minFaceWeight": 0.02,
                "minVolRatio": 0.005,
            },
        },
        "writeFlags": [],
        "mergeTolerance": 1e-6,
    }


#: What the meshing programs need of a case when :func:`write_layered_mesh` is used alone.
_UTILITY_DICTIONARIES: dict[str, dict[str, Any]] = {
    "controlDict": {
        "application": "simpleFoam",
        "startFrom": "startTime",
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": 1,
        "deltaT": 1,
        "writeControl": "timeStep",
        "writeInterval": 1,
    },
    "fvSchemes": {
        "ddtSchemes": {"default": "steadyState"},
        "gradSchemes": {"default": ("Gauss", "linear")},
        "divSchemes": {"default": "none"},
        "laplacianSchemes": {"default": ("Gauss", "linear", "corrected")},
        "interpolationSchemes": {"default": "linear"},
        "snGradSchemes": {"default": "corrected"},
    },
    "fvSolution": {"solvers": {}},
}


def thinnest_first_layer_m(background_cell_m: float) -> float:
    """The thinnest first layer (m) whose last layer is ``LAST_LAYER_MIN_FRACTION`` of the
    propeller's surface cell (the background cell halved ``SURFACE_LEVEL`` times)."""
    surface_cell = background_cell_m / 2.0**SURFACE_LEVEL
    return LAST_LAYER_MIN_FRACTION * surface_cell / LAYER_EXPANSION_RATIO ** (LAYERS - 1)


@dataclass(frozen=True)
class LayeredMesh:
    """What :func:`write_layered_mesh` wrote: the domain (m), the background cell and the first
    layer's height (m), the commands that make the mesh (run in the case folder)."""

    domain: Domain
    background_cell_m: float
    first_layer_m: float
    commands: list[list[str]]


def write_layered_mesh(
    surface_stl_path_mm: str | Path,
    diameter_mm: float,
    level: Level,
    out_case_dir: str | Path,
    first_layer_m: float,
    flow_sign: float = -1.0,
    domain_d: dict[str, float] | None = None,
    zone_radius_d: float = 0.6,
    zone_clearance_d: float = 0.1,
    surface_refinement: int = 0,
) -> LayeredMesh:
    """Write the dictionaries that mesh the propeller whose closed surface is
    ``surface_stl_path_mm`` (STL, mm, spin axis +z through the origin) with prism layers, into
    ``out_case_dir``; the commands to run (blockMesh, surfaceTransformPoints, surfaceFeatureExtract,
    snappyHexMesh, checkMesh) are returned, not run.

    ``diameter_mm`` is the tip diameter D; ``first_layer_m`` the coarse level's first-layer height
    in m (:func:`first_cell_height_m`; divided by the level's scale, and raised to
    :func:`thinnest_first_layer_m` where it is thinner); ``flow_sign`` -1 puts the inlet at +z;
    ``domain_d`` the box in D (``domain_radius``, ``upstream``, ``downstream``; default
    settings.DOMAIN_D); the rotating zone's radius and axial clearance are in D.
    ``surface_refinement`` halves the propeller's surface and edge cells that many times more; the
    layers stay the level's (sized on its own surface cell), as thinner ones were dropped or made
    the E63 blade diverge (the simulate how-to).
    """
    from torus_cad.simulate.settings import DOMAIN_D

    case, source = Path(out_case_dir), Path(surface_stl_path_mm)
    if not (math.isfinite(diameter_mm) and diameter_mm > 0.0):
        raise ParameterError(f"diameter = {diameter_mm:g} mm is out of range; allowed > 0 mm")
    points = read_stl_points_mm(source)
    if len(points) == 0 or not np.isfinite(points).all():
        raise ParameterError(f"surface {source.name!r} has no triangles or a non-finite vertex")
    reach = float(np.hypot(points[:, 0], points[:, 1]).max())
    if reach >= zone_radius_d * diameter_mm:
        raise ParameterError(
            f"surface {source.name!r} reaches {reach:.2f} mm from the axis, outside the rotating "
            f"zone's radius {zone_radius_d * diameter_mm:.2f} mm ({zone_radius_d:g} D): is D = "
            f"{diameter_mm:g} mm and the spin axis +z through the origin?"
        )
    domain = domain_around(
        points, diameter_mm, flow_sign, domain_d or DOMAIN_D, zone_radius_d, zone_clearance_d
    )
    scale = level_scale(level)
    cell = diameter_mm * MM_TO_M / BACKGROUND_CELLS_PER_D / scale
    first = max(first_layer_m / scale, thinnest_first_layer_m(cell))
    (case / SURFACE_MM).parent.mkdir(parents=True, exist_ok=True)
    if source.resolve() != (case / SURFACE_MM).resolve():
        (case / SURFACE_MM).write_bytes(source.read_bytes())
    _write(case / "system" / "blockMeshDict", block_mesh_dict(domain, cell))
    _write(
        case / "system" / "surfaceFeatureExtractDict",
        {
            "propeller.stl": {
                "extractionMethod": "extractFromSurface",
                "includedAngle": 150,
                "subsetFeatures": {"nonManifoldEdges": False, "openEdges": True},
                "writeObj": False,
            }
        },
    )
    _write(
        case / "system" / "snappyHexMeshDict", snappy_dict(domain, cell, first, surface_refinement)
    )
    # the meshing programs read them; the case's own win
    for name, entries in _UTILITY_DICTIONARIES.items():
        if not (case / "system" / name).exists():
            _write(case / "system" / name, entries)
    return LayeredMesh(domain, cell, first, [list(command) for command in MESH_COMMANDS])


@dataclass(frozen=True)
class MeshCheck:
    """checkMesh's verdict: ``ok`` (it printed "Mesh OK"), cells, cell types by name (hexahedra,
    prisms, wedges, pyramids, tet wedges, tetrahedra, polyhedra), the largest non-orthogonality
    (degrees) and the failed checks' lines."""

    ok: bool
    cells: int
    cell_types: dict[str, int]
    max_non_orthogonality: float | None
    failures: list[str]


def parse_check_mesh(log: str) -> MeshCheck:
    """Read checkMesh's output (v1912)."""
    types = {
        name: int(count)
        for name, count in re.findall(
            r"^\s+(hexahedra|prisms|wedges|pyramids|tet wedges|tetrahedra|polyhedra):\s+(\d+)",
            log,
            re.MULTILINE,
        )
    }
    cells = re.search(r"^\s+cells:\s+(\d+)", log, re.MULTILINE)
    ortho = re.search(r"Mesh non-orthogonality Max:\s+(\S+)", log)
    failures = [line.strip() for line in log.splitlines() if line.lstrip().startswith("***")]
    return MeshCheck(
        "Mesh OK." in log,
        int(cells.group(1)) if cells else 0,
        types,
        float(ortho.group(1)) if ortho else None,
        failures,
    )


def layer_coverage(log: str) -> dict[str, float] | None:
    """snappyHexMesh's layer report on the propeller: its face count, their mean layer count, the
    layers' mean overall thickness (m) and the share of the wanted thickness reached (0..1), the
    layers asked for (:func:`layer_count`) and ``coverage``, the mean layer count over them (0..1);
    None when the log has no report."""
    matches = re.findall(rf"^{WALL}\s+(\d+)\s+(\S+)\s+(\S+)\s+(\S+)\s*$", log, re.MULTILINE)
    if not matches:
        return None
    wanted = float(matches[0][1])  # the first table: the layers asked for
    faces, layers, thickness, percent = matches[-1]  # the last table: the layers kept
    return {
        "faces": float(faces),
        "wanted_layers": wanted,
        "mean_layers": float(layers),
        "thickness_m": float(thickness),
        "thickness_fraction": float(percent) / 100.0,
        "coverage": float(layers) / wanted,
    }
