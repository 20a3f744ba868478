"""README.txt written beside the CFD mesh: what the files are and how to import them."""

from __future__ import annotations

from typing import Any

_TEMPLATE = """\
Fluid domain of {name}, written by torus-cad cfd (gmsh {gmsh_version})
=========================================================================

Units: millimetres. Spin axis: z, through the origin. Flow enters at the "inlet" cap
(z = {inlet_z:.3f} mm) and leaves through the "outlet" cap (z = {outlet_z:.3f} mm).
Tip diameter D = {diameter:.3f} mm; outer cylinder radius {outer_radius:.3f} mm; rotating zone
radius {zone_radius:.3f} mm spanning z = {zone_low:.3f} .. {zone_high:.3f} mm.

Files
  {name}_cfd.msh     gmsh mesh format 4.1 (ASCII): current gmsh, meshio, most converters
  {name}_cfd_v2.msh  gmsh mesh format 2.2 (ASCII): what OpenFOAM's gmshToFoam reads
  {name}_cfd.step    the propeller B-rep the domain was cut from
  {name}_cfd.json    element counts, quality (SICN), volumes, settings, times

Mesh: {tets:,} linear tetrahedra ({zone_tets:,} in rotating_zone, {fluid_tets:,} in fluid), worst SICN {sicn:.3f}.
The two regions share their interface node for node (conformal): no interpolation is needed
for a frozen-rotor (MRF) run; for a sliding mesh the interface is split into an AMI pair.

Physical groups
  propeller           surface  the propeller's wall (hub and blades)
  rotating_interface  surface  between rotating_zone and fluid (internal)
  inlet               surface  inflow cap
  outlet              surface  outflow cap
  farfield            surface  outer lateral surface (slip wall or freestream)
  rotating_zone       volume   the cylinder around the propeller that turns with it
  fluid               volume   the stationary outer region

OpenFOAM (these steps were run with OpenFOAM v1912)
  A runnable case (boundary conditions, MRF, k-omega SST, an Allrun script) comes from
      torus-cad simulate CONFIG --rpm RPM --mesher tet --case-only --out FOLDER
  which meshes such a domain again at the sizes of its --level. To import this mesh by hand
  instead: make an empty case folder inside this folder (mkdir case && cd case) and run the lines
  between BEGIN and END in a POSIX shell (sh or bash; they are indented by 4 spaces here). MESH is
  the folder of this README, .. from the case folder; for a case elsewhere, set MESH first.
  The steps name no absolute path, so they still work after this folder is moved.
  - gmshToFoam needs system/controlDict, checkMesh also system/fvSchemes and fvSolution:
    the first lines write minimal ones (replace them with your solver's).
  - gmshToFoam turns the boundary groups into patches (propeller, inlet, outlet, farfield),
    the volumes into cellZones (rotating_zone, fluid) and the internal rotating_interface into
    a faceZone of {interface:,} faces. It also leaves an EMPTY patch rotating_interface (0 faces;
    every field file would have to name it): createPatch with an empty list removes it (and any
    other patch without faces) and keeps the faceZone.
  - Every patch arrives as type patch: the propeller is made a wall.
  - gmshToFoam prints many "Not using gmsh face" warnings and may add faces to a patch
    defaultFaces that ends up empty; createPatch removes that too.
  - On Debian and Ubuntu (package openfoam) the commands are in /usr/bin and need only
    WM_PROJECT_DIR; elsewhere source OpenFOAM's etc/bashrc first.

  BEGIN
    MESH="${{MESH:-..}}"
    export WM_PROJECT_DIR="${{WM_PROJECT_DIR:-/usr/share/openfoam}}"
    mkdir -p system
    echo 'FoamFile {{ version 2.0; format ascii; class dictionary; object controlDict; }} application simpleFoam; startFrom startTime; startTime 0; stopAt endTime; endTime 100; deltaT 1; writeControl timeStep; writeInterval 100;' > system/controlDict
    echo 'FoamFile {{ version 2.0; format ascii; class dictionary; object fvSchemes; }} ddtSchemes {{ default steadyState; }} gradSchemes {{ default Gauss linear; }} divSchemes {{ default none; }} laplacianSchemes {{ default Gauss linear corrected; }} interpolationSchemes {{ default linear; }} snGradSchemes {{ default corrected; }}' > system/fvSchemes
    echo 'FoamFile {{ version 2.0; format ascii; class dictionary; object fvSolution; }}' > system/fvSolution
    echo 'FoamFile {{ version 2.0; format ascii; class dictionary; object createPatchDict; }} pointSync false; patches ();' > system/createPatchDict
    gmshToFoam "$MESH/{name}_cfd_v2.msh" > log.gmshToFoam
    transformPoints -scale '(0.001 0.001 0.001)' > log.transformPoints
    createPatch -overwrite > log.createPatch
    foamDictionary constant/polyMesh/boundary -entry entry0/propeller/type -set wall > /dev/null
    checkMesh > log.checkMesh && grep 'Mesh OK' log.checkMesh
  END

  transformPoints scales millimetres to metres (OpenFOAM.com v2012 and later also take
  -scale 0.001). Then:
  - Frozen rotor (MRF): constant/MRFProperties with cellZone rotating_zone, origin (0 0 0),
    axis (0 0 1), omega in rad/s (negative for the default 'cw' blade, which pushes air
    toward -z when it turns clockwise seen from +z), nonRotatingPatches ().
  - Sliding mesh (AMI): createBaffles -overwrite with a createBafflesDict that turns faceZone
    rotating_interface into two cyclicAMI patches (e.g. AMI1 / AMI2, transform noOrdering);
    then a solidBody rotating motion of cellZone rotating_zone in constant/dynamicMeshDict.
  - Field files (0/U, 0/p, ...) name the patches propeller, inlet, outlet and farfield.

Other tools
  gmsh {name}_cfd.msh                          look at it (Tools > Visibility lists the groups)
  gmsh {name}_cfd.msh -format su2 -o {name}.su2 -save   SU2, groups become markers
  meshio convert {name}_cfd.msh {name}.vtu     ParaView and friends
"""  # noqa: E501 (code or text written out verbatim)


#: The lines of README.txt's OpenFOAM block lie between these (indented by 4 spaces).
BLOCK_BEGIN, BLOCK_END = "  BEGIN", "  END"


def readme_text(name: str, report: dict[str, Any]) -> str:
    """The README.txt for a CFD mesh, from its report (see ``cfd.domain.write_cfd_domain``); it
    names no absolute path, so the folder can move."""
    domain = report["domain_mm"]
    return _TEMPLATE.format(
        name=name,
        gmsh_version=report["gmsh_version"],
        inlet_z=domain["inlet_z"],
        outlet_z=domain["outlet_z"],
        diameter=domain["tip_diameter"],
        outer_radius=domain["outer_radius"],
        zone_radius=domain["zone_radius"],
        zone_low=domain["zone_z"][0],
        zone_high=domain["zone_z"][1],
        tets=report["tetrahedra_total"],
        zone_tets=report["tetrahedra"]["rotating_zone"],
        fluid_tets=report["tetrahedra"]["fluid"],
        sicn=report["sicn_min"],
        interface=report["triangles"]["rotating_interface"],
    )


def openfoam_block(text: str) -> str:
    """The shell lines of a README.txt's OpenFOAM block (between BEGIN and END, unindented)."""
    lines = text.splitlines()
    start, end = lines.index(BLOCK_BEGIN), lines.index(BLOCK_END)
    return "\n".join(line[4:] for line in lines[start + 1 : end]) + "\n"
