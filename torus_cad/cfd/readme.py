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
  {name}.step        the propeller B-rep the domain was cut from
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

OpenFOAM
  1. In a case folder:        gmshToFoam {name}_cfd_v2.msh
     Boundary physical groups become patches (propeller, inlet, outlet, farfield), physical
     volumes become cellZones (rotating_zone, fluid), and the internal rotating_interface
     becomes a faceZone.
  2. Millimetres to metres:   transformPoints -scale '(0.001 0.001 0.001)'
     (OpenFOAM.com v2012 and later: transformPoints -scale 0.001)
  3. Set the patch types in constant/polyMesh/boundary: propeller -> wall, farfield -> patch
     or wall (slip); inlet and outlet stay patch.
  4a. Frozen rotor (MRF): constant/MRFProperties with cellZone rotating_zone,
      origin (0 0 0), axis (0 0 1), omega in rad/s.
  4b. Sliding mesh (AMI): createBaffles -overwrite with a createBafflesDict that turns faceZone
      rotating_interface into two cyclicAMI patches (e.g. AMI1 / AMI2, transform noOrdering);
      then a solidBody rotating motion of cellZone rotating_zone in constant/dynamicMeshDict.
  5. checkMesh

Other tools
  gmsh {name}_cfd.msh                          look at it (Tools > Visibility lists the groups)
  gmsh {name}_cfd.msh -format su2 -o {name}.su2 -save   SU2, groups become markers
  meshio convert {name}_cfd.msh {name}.vtu     ParaView and friends
"""


def readme_text(name: str, report: dict[str, Any]) -> str:
    """The README.txt for a CFD mesh, from its report (see ``cfd.domain.write_cfd_domain``)."""
    domain = report["domain_mm"]
    return _TEMPLATE.format(
        name=name, gmsh_version=report["gmsh_version"], inlet_z=domain["inlet_z"], outlet_z=domain["outlet_z"],
        diameter=domain["tip_diameter"], outer_radius=domain["outer_radius"], zone_radius=domain["zone_radius"],
        zone_low=domain["zone_z"][0], zone_high=domain["zone_z"][1], tets=report["tetrahedra_total"],
        zone_tets=report["tetrahedra"]["rotating_zone"], fluid_tets=report["tetrahedra"]["fluid"],
        sicn=report["sicn_min"])
