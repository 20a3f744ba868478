"""A toroidal propeller for cq-editor: edit the numbers below, press Render (F5).

* In cq-editor (File > Open this script) the propeller appears through ``show_object``.
* Run as plain ``python scripts/cq_editor_propeller.py`` it builds the same propeller and
  writes the same output set as ``torus-cad build --preview`` into ``OUT_DIR``: ``<name>.step``,
  ``<name>.stl``, ``<name>.png``, the blade-element table and ``<name>.json``.

Units: mm and degrees. The spin axis is z; the hub is centred at the origin. Control points are
in the hub frame L: [x_L degrees around the axis, y_L mm down the axis from 1 mm below the hub's
top face, z_L mm radially out from R - R/8]. ``torus-cad defaults`` explains every parameter.
"""

# --- parameters: edit in place -------------------------------------------------------------
DESIGN = None  # or "my_prop.toml": start from a design file
# dotted keys as in the TOML; any key of `torus-cad defaults`
CHANGES = {
    "name": "torus_propeller",
    "blades": 3,  # 1..12
    "phase_deg": 0.0,  # angle of blade 0 around the axis
    "hub.radius": 10.0,  # R, mm
    "hub.length": 20.0,  # L, mm (the hub spans z in [-L/2, L/2])
    "airfoil.max_camber": 0.02,  # NACA m, fraction of the chord (0 = symmetric)
    "airfoil.camber_position": 0.4,  # NACA p
    "airfoil.thickness": 0.5,  # maximum thickness, fraction of the chord
    "centerline.p2": [25.0, 3.0, 22.0],  # [x_L deg, y_L mm, z_L mm]
    "centerline.p3": [75.0, 15.0, 22.0],
    # [x_L deg, y_L mm]; z_L = 0 (the blade ends in the hub)
    "centerline.p4": [100.0, 18.0],
    # Quartics in s in [0, 1], highest power first: a s^4 + b s^3 + c s^2 + d s + e
    "transforms.angle_of_attack": [0.0, 0.0, 0.0, 0.0, 20.0],  # degrees
    "transforms.scale_x": [0.0, 0.0, -16.0, 16.0, 6.0],  # chord, mm (> 0)
    "transforms.scale_y": [0.0, 0.0, -4.0, 4.0, 2.0],  # thickness scale, mm (> 0)
    "resolution.sections": 25,  # sections along the blade (fewer = faster)
    "resolution.points": 80,  # points around each section
}

# Plain-python run only:
OUT_DIR = "step_out"
DENSITY_G_CM3 = 1.24  # PLA
# --------------------------------------------------------------------------------------------

import sys  # noqa: E402
from pathlib import Path  # noqa: E402

try:
    from torus_cad.propeller import Propeller, propeller_objects
# a checkout without the package installed (cq-editor may not set __file__)
except ModuleNotFoundError:
    sys.path.insert(0, str(Path(globals().get("__file__", "scripts/x.py")).resolve().parent.parent))
    from torus_cad.propeller import Propeller, propeller_objects


result: Propeller = propeller_objects(DESIGN, overrides=CHANGES)
NAME = result.parameters.name
# the fused propeller as a cq.Workplane (result.hub, result.blades: the parts)
propeller = result.workplane

if "show_object" in globals():  # cq-editor (or anything else that injects show_object)
    show_object(propeller, name=NAME)  # type: ignore[name-defined]  # noqa: F821
else:
    from torus_cad.outputs.output_set import write_output_set
    from torus_cad.preview.picture import write_preview

    # The same output set as 'torus-cad build --preview': the blade-element table and the picture
    # belong to it, so a run after a build replaces that build's files instead of dropping some.
    written = write_output_set(
        result,
        Path(OUT_DIR),
        DENSITY_G_CM3,
        sections_table=True,
        extra_files={"png": lambda path: write_preview(result, path)},
    ).paths
    for path in written.values():
        print(f"wrote {path}")
    properties = result.mass_properties(DENSITY_G_CM3)
    print(
        f"volume {properties.volume_mm3:.3f} mm^3, mass "
        f"{properties.mass_g:.3f} g at {DENSITY_G_CM3:g} g/cm^3"
    )
