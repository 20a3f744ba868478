"""The OpenFOAM case of a simulation, written through foamlib's FoamFile / FoamFieldFile
dictionaries.

A steady frozen-rotor (MRF) run of simpleFoam with k-omega SST and wall functions, on a
snappyHexMesh mesh with prism layers on the propeller (torus_cad.simulate.snappy, the default) or on
the ``cfd`` command's tetrahedra (mm, converted with gmshToFoam and scaled to m; ``Mesher.TET``).
The first layer is sized for y+ 1, where OpenFOAM v1912's ``nutkWallFunction`` gives nut = 0 and
``omegaWallFunction`` the viscous-sublayer omega: the wall functions then act as the
low-Reynolds-number wall condition (they switch to the log law where y+ is above about 11, e.g.
where snappyHexMesh left out layers).
Boundaries:

* still air (airspeed 0): inlet and far field take in air at total pressure 0
  (``totalPressure`` + ``pressureInletOutletVelocity``), the outlet is at static pressure 0;
* airspeed > 0: a uniform inflow at the inlet, the far field a slip wall, the outlet at static
  pressure 0.

The propeller is a wall that turns with the MRF zone (its velocity is set by the zone). Function
objects record the propeller's force and moment about the spin axis (``forces``), the residuals
(``solverInfo``), y+ on the walls at the last iteration (``yPlus``), the propeller's surface
pressure at the last iteration (``surfaces``, VTK PolyData, for the tonal noise of
torus_cad.acoustics) and, for the momentum balance, the momentum flux (``surfaceFieldValue``: sum of
U phi) and the pressure and viscous force (``forces``) on each outer patch.

The commands that mesh and run the case are :func:`commands`; ``Allrun`` lists the same ones.
"""

from __future__ import annotations

import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from foamlib import Dimensioned, DimensionSet, FoamFieldFile, FoamFile

from torus_cad.parameters.design import Handedness
from torus_cad.simulate.settings import (
    TURBULENCE_INTENSITY,
    Mesher,
    OperatingPoint,
    TurbulenceModel,
    transition_onset_re_theta,
)
from torus_cad.simulate.snappy import MESH_COMMANDS as LAYERED_MESH_COMMANDS

#: Patches of the cfd mesh (torus_cad.cfd_domain.domain.SURFACE_GROUPS) as the case types them.
WALL, OUTER_PATCHES, INTERFACE = "propeller", ("inlet", "outlet", "farfield"), "rotating_interface"
ZONE = "rotating_zone"
MM_TO_M = "(0.001 0.001 0.001)"
#: Names of the function objects (their folders under postProcessing/).
FORCES, RESIDUALS, OUTER_FORCES, Y_PLUS = "propeller_forces", "residuals", "outer_forces", "yPlus"
#: The function object that writes the propeller's surface pressure (face values, kinematic p in
#: m^2/s^2) at the last time as VTK PolyData: ``postProcessing/<BLADE_PRESSURE>/<time>/<WALL>.vtp``
#: (torus_cad.acoustics.pressure_surface).
BLADE_PRESSURE = "blade_pressure"
MOMENTUM_FLUX = {patch: f"momentum_flux_{patch}" for patch in OUTER_PATCHES}
FIELDS = ("U", "p", "k", "omega")
#: The transition model's extra fields (kOmegaSSTLM): intermittency and transition-onset Re_theta.
TRANSITION_FIELDS = ("gammaInt", "ReThetat")


@dataclass(frozen=True)
class CaseSpec:
    """What the dictionaries need: the operating point, handedness, D (m), flow direction (+1/-1
    along z from inlet to outlet), iterations, processes, the gmsh mesh file relative to the case
    (``tet`` route) the mesher and the turbulence model."""

    point: OperatingPoint
    handedness: Handedness
    diameter_m: float
    flow_sign: float
    iterations: int
    processes: int
    msh_file: str
    mesher: Mesher = Mesher.SNAPPY
    turbulence: TurbulenceModel = TurbulenceModel.K_OMEGA_SST

    @property
    def fields(self) -> tuple[str, ...]:
        """The solved fields whose residuals are recorded."""
        return FIELDS + (
            TRANSITION_FIELDS if self.turbulence == TurbulenceModel.K_OMEGA_SST_LM else ()
        )

    @property
    def inflow(self) -> tuple[float, float, float]:
        return (0.0, 0.0, self.flow_sign * self.point.airspeed_m_s)

    @property
    def still_air(self) -> bool:
        return self.point.airspeed_m_s == 0.0


def _write(path: Path, entries: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with FoamFile(path) as dictionary:
        for key, value in entries.items():
            dictionary[key] = value


def control_dict(spec: CaseSpec) -> dict[str, Any]:
    rho = spec.point.fluid.density_kg_m3
    forces = {
        "type": "forces",
        "libs": ['"libforces.so"'],
        "writeControl": "timeStep",
        "writeInterval": 1,
        "rho": "rhoInf",
        "rhoInf": rho,
        "CofR": [0, 0, 0],
        "log": False,
    }
    functions: dict[str, Any] = {
        FORCES: {**forces, "patches": [WALL]},
        OUTER_FORCES: {**forces, "patches": list(OUTER_PATCHES)},
        Y_PLUS: {
            "type": "yPlus",
            "libs": ['"libfieldFunctionObjects.so"'],
            "writeControl": "writeTime",
            "log": False,
        },
        BLADE_PRESSURE: {
            "type": "surfaces",
            "libs": ['"libsampling.so"'],
            "writeControl": "writeTime",
            "surfaceFormat": "vtk",
            "formatOptions": {"vtk": {"format": "binary", "legacy": False}},
            "fields": ["p"],
            "interpolationScheme": "cell",
            "surfaces": {WALL: {"type": "patch", "patches": [WALL], "interpolate": False}},
        },
        RESIDUALS: {
            "type": "solverInfo",
            "libs": ['"libutilityFunctionObjects.so"'],
            "fields": list(spec.fields),
            "writeControl": "timeStep",
            "writeInterval": 1,
        },
    }
    for patch, name in MOMENTUM_FLUX.items():
        functions[name] = {
            "type": "surfaceFieldValue",
            "libs": ['"libfieldFunctionObjects.so"'],
            "writeControl": "timeStep",
            "writeInterval": 1,
            "log": False,
            "writeFields": False,
            "regionType": "patch",
            "name": patch,
            "operation": "weightedSum",
            "weightField": "phi",
            "fields": ["U"],
        }
    return {
        "application": "simpleFoam",
        "startFrom": "startTime",
        "startTime": 0,
        "stopAt": "endTime",
        "endTime": spec.iterations,
        "deltaT": 1,
        "writeControl": "timeStep",
        "writeInterval": spec.iterations,
        "purgeWrite": 0,
        "writeFormat": "binary",
        "writePrecision": 8,
        "writeCompression": False,
        "timeFormat": "general",
        "timePrecision": 6,
        "runTimeModifiable": False,
        "functions": functions,
    }


FV_SCHEMES: dict[str, Any] = {
    "ddtSchemes": {"default": "steadyState"},
    "gradSchemes": {
        "default": ("Gauss", "linear"),
        "grad(U)": ("cellLimited", "Gauss", "linear", 1),
        "grad(k)": ("cellLimited", "Gauss", "linear", 1),
        "grad(omega)": ("cellLimited", "Gauss", "linear", 1),
    },
    "divSchemes": {
        "default": "none",
        "div(phi,U)": ("bounded", "Gauss", "linearUpwind", "grad(U)"),
        "div(phi,k)": ("bounded", "Gauss", "upwind"),
        "div(phi,omega)": ("bounded", "Gauss", "upwind"),
        "div(phi,gammaInt)": ("bounded", "Gauss", "upwind"),
        "div(phi,ReThetat)": ("bounded", "Gauss", "upwind"),
        "div((nuEff*dev2(T(grad(U)))))": ("Gauss", "linear"),
    },
    "laplacianSchemes": {"default": ("Gauss", "linear", "limited", "corrected", 0.5)},
    "interpolationSchemes": {"default": "linear"},
    "snGradSchemes": {"default": ("limited", "corrected", 0.5)},
    "wallDist": {"method": "meshWave"},
}

FV_SOLUTION: dict[str, Any] = {
    "solvers": {
        "p": {"solver": "GAMG", "smoother": "GaussSeidel", "tolerance": 1e-7, "relTol": 0.05},
        '"(U|k|omega|gammaInt|ReThetat)"': {
            "solver": "smoothSolver",
            "smoother": "symGaussSeidel",
            "tolerance": 1e-8,
            "relTol": 0.1,
        },
    },
    "SIMPLE": {
        "nNonOrthogonalCorrectors": 1,
        "consistent": False,
        "residualControl": {"p": 1e-5, "U": 1e-6, '"(k|omega)"': 1e-6},
    },
    "relaxationFactors": {
        "fields": {"p": 0.3},
        "equations": {"U": 0.7, '"(k|omega|gammaInt|ReThetat)"': 0.7},
    },
}


def mrf_properties(spec: CaseSpec) -> dict[str, Any]:
    return {
        "MRF1": {
            "cellZone": ZONE,
            "active": True,
            "nonRotatingPatches": [],
            "origin": [0, 0, 0],
            "axis": [0, 0, 1],
            "omega": spec.point.omega_rad_s(spec.handedness),
        }
    }


def _boundaries(spec: CaseSpec, field: str, inflow_value: Any) -> dict[str, Any]:
    """boundaryField of ``field`` ("U", "p", "k", "omega", "nut", "gammaInt", "ReThetat") on every
    patch."""
    zero_gradient = {"type": "zeroGradient"}
    inlet_outlet = {"type": "inletOutlet", "inletValue": inflow_value, "value": inflow_value}
    if field == "U":
        opening = {"type": "pressureInletOutletVelocity", "value": inflow_value}
        inlet = opening if spec.still_air else {"type": "fixedValue", "value": inflow_value}
        side = opening if spec.still_air else {"type": "slip"}
        return {
            "inlet": inlet,
            "farfield": side,
            "outlet": inlet_outlet,
            WALL: {"type": "fixedValue", "value": [0, 0, 0]},
            INTERFACE: zero_gradient,
        }
    if field == "p":
        opening = {"type": "totalPressure", "p0": 0, "value": 0}
        fixed = {"type": "fixedValue", "value": 0}
        return {
            "inlet": opening if spec.still_air else zero_gradient,
            "farfield": opening if spec.still_air else {"type": "slip"},
            "outlet": fixed,
            WALL: zero_gradient,
            INTERFACE: zero_gradient,
        }
    if field == "nut":
        calculated = {"type": "calculated", "value": 0}
        return {
            **{patch: calculated for patch in OUTER_PATCHES},
            INTERFACE: calculated,
            WALL: {"type": "nutkWallFunction", "value": 0},
        }
    wall_types = {"k": "kqRWallFunction", "omega": "omegaWallFunction"}
    wall = (
        {"type": wall_types[field], "value": inflow_value} if field in wall_types else zero_gradient
    )
    inlet = inlet_outlet if spec.still_air else {"type": "fixedValue", "value": inflow_value}
    return {
        "inlet": inlet,
        "farfield": inlet_outlet if spec.still_air else {"type": "slip"},
        "outlet": inlet_outlet,
        WALL: wall,
        INTERFACE: zero_gradient,
    }


def _write_field(
    path: Path, dimensions: DimensionSet, value: Any, boundaries: dict[str, Any]
) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    field = FoamFieldFile(path)
    with field:
        field.dimensions = dimensions
        field.internal_field = value
        field.boundary_field = boundaries


def write_fields(case: Path, spec: CaseSpec) -> None:
    """0/U, p, k, omega, nut (and gammaInt, ReThetat for kOmegaSSTLM): the inflow everywhere to
    start from."""
    k, omega = spec.point.inflow_turbulence(spec.diameter_m)
    inflow = list(spec.inflow)
    values = {
        "U": (DimensionSet(length=1, time=-1), inflow),
        "p": (DimensionSet(length=2, time=-2), 0),
        "k": (DimensionSet(length=2, time=-2), k),
        "omega": (DimensionSet(time=-1), omega),
        "nut": (DimensionSet(length=2, time=-1), 0),
    }
    if spec.turbulence == TurbulenceModel.K_OMEGA_SST_LM:
        values["gammaInt"] = (DimensionSet(), 1.0)
        values["ReThetat"] = (DimensionSet(), transition_onset_re_theta(TURBULENCE_INTENSITY))
    for name, (dimensions, value) in values.items():
        _write_field(case / "0" / name, dimensions, value, _boundaries(spec, name, value))


def write_operating_point(case: Path, spec: CaseSpec) -> None:
    """The files that depend on the operating point: MRFProperties, 0/ and controlDict
    (iterations)."""
    _write(case / "constant" / "MRFProperties", mrf_properties(spec))
    _write(case / "system" / "controlDict", control_dict(spec))
    write_fields(case, spec)


def write_dictionaries(case: Path, spec: CaseSpec) -> None:
    """Every dictionary of the case (the mesh itself comes from :func:`mesh_commands`). The parallel
    decomposition cuts along x (through the axis: each part gets its share of the propeller), with
    the ``simple`` method, which every OpenFOAM build has (scotch is optional)."""
    fluid = spec.point.fluid
    write_operating_point(case, spec)
    _write(case / "system" / "fvSchemes", FV_SCHEMES)
    _write(case / "system" / "fvSolution", FV_SOLUTION)
    _write(
        case / "system" / "decomposeParDict",
        {
            "numberOfSubdomains": spec.processes,
            "method": "simple",
            "coeffs": {"n": [spec.processes, 1, 1], "delta": 0.001},
        },
    )
    _write(
        case / "constant" / "transportProperties",
        {
            "transportModel": "Newtonian",
            "nu": Dimensioned(fluid.viscosity_m2_s, DimensionSet(length=2, time=-1), "nu"),
            "rho": Dimensioned(fluid.density_kg_m3, DimensionSet(mass=1, length=-3), "rho"),
        },
    )
    _write(
        case / "constant" / "turbulenceProperties",
        {
            "simulationType": "RAS",
            "RAS": {"RASModel": spec.turbulence.value, "turbulence": True, "printCoeffs": False},
        },
    )


def mesh_commands(spec: CaseSpec) -> list[list[str]]:
    """The ``snappy`` route: torus_cad.simulate.snappy.MESH_COMMANDS (blockMesh ... snappyHexMesh,
    checkMesh). The ``tet`` route: convert the gmsh mesh, scale it to metres, make the propeller a
    wall, check it."""
    if spec.mesher == Mesher.SNAPPY:
        return [list(command) for command in LAYERED_MESH_COMMANDS]
    return [
        ["gmshToFoam", spec.msh_file],
        ["transformPoints", "-scale", MM_TO_M],
        [
            "foamDictionary",
            "constant/polyMesh/boundary",
            "-entry",
            f"entry0/{WALL}/type",
            "-set",
            "wall",
        ],
        ["checkMesh"],
    ]


def solve_commands(spec: CaseSpec) -> list[list[str]]:
    """The solver (with decomposePar / reconstructPar around it in parallel); mpiexec is added by
    the runner."""
    if spec.processes == 1:
        return [["simpleFoam"]]
    return [["decomposePar", "-force"], ["simpleFoam"], ["reconstructPar", "-latestTime"]]


def allrun_text(spec: CaseSpec) -> str:
    """A POSIX shell script that repeats the run by hand, step for step."""
    lines = [
        "#!/bin/sh",
        "# Repeats torus-cad simulate's run of this case (OpenFOAM v1912 on PATH).",
        "# Logs go to log.<command>; results to postProcessing/ and the last time folder.",
        'cd "${0%/*}" || exit 1',
        "set -e",
        "# Debian's openfoam package: its programs find etc/ through WM_PROJECT_DIR",
        '[ -n "${WM_PROJECT_DIR:-}" ] || [ ! -d /usr/share/openfoam/etc '
        "] || export WM_PROJECT_DIR=/usr/share/openfoam",
    ]
    if spec.processes > 1:
        lines += [
            "# As root (a container), OpenMPI's mpiexec refuses to start without these two",
            'if [ "$(id -u)" -eq 0 ]; then export '
            "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1; fi",
        ]
    for command in mesh_commands(spec) + solve_commands(spec):
        if command == ["simpleFoam"] and spec.processes > 1:
            command = ["mpiexec", "-n", str(spec.processes), "simpleFoam", "-parallel"]
        lines.append(
            f"{shlex.join(command)} > log."
            f"{command[0] if command[0] != 'mpiexec' else 'simpleFoam'} 2>&1"
        )
        if command == ["checkMesh"]:
            lines.append(
                "grep -q 'Mesh OK' log.checkMesh || { echo 'checkMesh "
                "did not report Mesh OK: see log.checkMesh' >&2; "
                "exit 1; }"
            )
    return "\n".join(lines) + "\n"


def write_case(case: Path, spec: CaseSpec) -> None:
    """Every dictionary and the ``Allrun`` script (executable)."""
    write_dictionaries(case, spec)
    allrun = case / "Allrun"
    allrun.write_text(allrun_text(spec))
    allrun.chmod(0o755)
