"""A toroidal propeller for cq-editor: edit the numbers below, press Render (F5).

* In cq-editor (File > Open this script) the propeller appears through ``show_object``.
* Run as plain ``python scripts/cq_editor_propeller.py`` it builds the same propeller and
  writes ``<NAME>.step``, ``<NAME>.stl``, ``<NAME>.json`` and ``<NAME>.png`` into ``OUT_DIR``.

Units: mm and degrees. The spin axis is z; the hub is centred at the origin. Control points are
in the hub frame L: [x_L degrees around the axis, y_L mm down the axis from 1 mm below the hub's
top face, z_L mm radially out from R - R/8]. ``torus-cad defaults`` explains every parameter.
"""

# --- parameters: edit in place -------------------------------------------------------------
NAME = "torus_propeller"
BLADES = 3                                   # 1..12
PHASE_DEG = 0.0                              # angle of blade 0 around the axis

HUB_RADIUS = 10.0                            # R, mm
HUB_LENGTH = 20.0                            # L, mm (the hub spans z in [-L/2, L/2])

MAX_CAMBER = 0.02                            # NACA m, fraction of the chord (0 = symmetric)
CAMBER_POSITION = 0.4                        # NACA p
THICKNESS = 0.5                              # maximum thickness, fraction of the chord

CENTERLINE_P2 = (25.0, 3.0, 22.0)            # [x_L deg, y_L mm, z_L mm]
CENTERLINE_P3 = (75.0, 15.0, 22.0)
CENTERLINE_P4 = (100.0, 18.0)                # [x_L deg, y_L mm]; z_L = 0 (the blade ends in the hub)

# Quartics in s in [0, 1], highest power first: a s^4 + b s^3 + c s^2 + d s + e
ANGLE_OF_ATTACK = (0.0, 0.0, 0.0, 0.0, 20.0)  # degrees
SCALE_X = (0.0, 0.0, -16.0, 16.0, 6.0)        # chord, mm (> 0)
SCALE_Y = (0.0, 0.0, -4.0, 4.0, 2.0)          # thickness scale, mm (> 0)

SECTIONS = 25                                # sections along the blade (fewer = faster)
POINTS = 80                                  # points around each section

# Plain-python run only:
OUT_DIR = "step_out"
DENSITY_G_CM3 = 1.24                         # PLA
# --------------------------------------------------------------------------------------------

import sys  # noqa: E402
from pathlib import Path  # noqa: E402

try:
    from torus_cad.cadquery_api import PropellerObjects, propeller_objects
except ModuleNotFoundError:  # a checkout without the package installed (cq-editor may not set __file__)
    sys.path.insert(0, str(Path(globals().get("__file__", "scripts/x.py")).resolve().parent.parent))
    from torus_cad.cadquery_api import PropellerObjects, propeller_objects


def build() -> PropellerObjects:
    """The propeller of the parameters above, as CadQuery objects."""
    return propeller_objects(overrides={
        "name": NAME, "blades": BLADES, "phase_deg": PHASE_DEG,
        "hub.radius": HUB_RADIUS, "hub.length": HUB_LENGTH,
        "airfoil.max_camber": MAX_CAMBER, "airfoil.camber_position": CAMBER_POSITION,
        "airfoil.thickness": THICKNESS,
        "centerline.p2": list(CENTERLINE_P2), "centerline.p3": list(CENTERLINE_P3),
        "centerline.p4": list(CENTERLINE_P4),
        "transforms.angle_of_attack": list(ANGLE_OF_ATTACK), "transforms.scale_x": list(SCALE_X),
        "transforms.scale_y": list(SCALE_Y),
        "resolution.sections": SECTIONS, "resolution.points": POINTS,
    })


result = build()
propeller = result.workplane  # the fused propeller as a cq.Workplane (result.hub, result.blades: the parts)

if "show_object" in globals():  # cq-editor (or anything else that injects show_object)
    show_object(propeller, name=NAME)  # type: ignore[name-defined]  # noqa: F821
else:
    from torus_cad.preview import write_preview

    written = result.write(OUT_DIR, density_g_cm3=DENSITY_G_CM3)
    written["png"] = write_preview(result, Path(OUT_DIR) / f"{NAME}.png")
    for path in written.values():
        print(f"wrote {path}")
    properties = result.mass_properties(DENSITY_G_CM3)
    print(f"volume {properties.volume_mm3:.3f} mm^3, mass {properties.mass_g:.3f} g at {DENSITY_G_CM3:g} g/cm^3")
