"""Check the STL triangle estimate against OpenCascade's real triangle counts.

    python scripts/stl_budget.py              # 7 designs x 7 deflection settings, prints a table
    python scripts/stl_budget.py --quick      # 3 designs x 6 settings
    python scripts/stl_budget.py --design thin --design "1 blade"

For each design and (linear, angular) deflection it prints the estimate that the build checks
against the limit before tessellating (torus_cad.design.stl_budget), the triangles BRepMesh
really makes, their ratio and the tessellation time. Settings whose estimate is above --max-estimate
are skipped (BRepMesh's time grows faster than its triangle count on the lofted blades).
"""

from __future__ import annotations

import argparse
import sys
import time

DESIGNS = {
    "default": {},
    "1 blade": {"blades": 1},
    "6 blades, hub 16": {"blades": 6, "hub.radius": 16.0},
    "thin": {"airfoil.thickness": 0.12, "airfoil.max_camber": 0.06},
    "wide chord": {"transforms.scale_x": [0.0, 0.0, -24.0, 24.0, 7.0], "hub.radius": 14.0},
    "twisted": {
        "transforms.angle_of_attack": [0.0, 0.0, 0.0, 60.0, -10.0],
        "centerline.frame": "rotation_minimizing",
    },
    "fine sampling": {"resolution.sections": 100, "resolution.points": 400},
}
SETTINGS = [
    (0.5, 0.5),
    (0.1, 0.2),
    (0.05, 0.1),
    (0.01, 0.2),
    (0.5, 0.1),
    (0.002, 0.5),
    (0.05, 0.05),
]
QUICK_DESIGNS = ("default", "1 blade", "thin")
QUICK_SETTINGS = [(0.5, 0.5), (0.1, 0.3), (0.05, 0.2), (0.01, 0.2), (0.05, 0.1), (0.002, 0.5)]


def real_triangles(solid, linear: float, angular: float) -> tuple[int, float]:
    """Triangles BRepMesh makes for ``solid`` (a fresh copy) and the seconds it took."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepMesh import BRepMesh_IncrementalMesh
    from OCP.TopLoc import TopLoc_Location

    shape = solid.copy()
    start = time.perf_counter()
    BRepMesh_IncrementalMesh(shape.wrapped, linear, False, angular, True)
    seconds = time.perf_counter() - start
    count = 0
    for face in shape.Faces():
        triangulation = BRep_Tool.Triangulation_s(face.wrapped, TopLoc_Location())
        count += 0 if triangulation is None else triangulation.NbTriangles()
    return count, seconds


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="3 designs x 6 settings")
    parser.add_argument(
        "--design", action="append", choices=list(DESIGNS), help="only these designs (repeatable)"
    )
    parser.add_argument(
        "--max-estimate", type=float, default=400_000, help="skip settings estimated above this"
    )
    args = parser.parse_args()
    from torus_cad.design.stl_budget import estimated_stl_triangles
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller

    names = args.design or (QUICK_DESIGNS if args.quick else tuple(DESIGNS))
    settings = QUICK_SETTINGS if args.quick else SETTINGS
    print(
        f"{'design':<18} {'linear':>7} {'angular':>7}"
        f" {'estimate':>9} {'real':>9} {'ratio':>6} {'mesh s':>7}"
    )
    ratios = []
    for name in names:
        params = PropellerParameters().with_values(DESIGNS[name])
        propeller = build_propeller(params)
        for linear, angular in settings:
            design = params.with_values(
                {"export.stl_linear_deflection": linear, "export.stl_angular_deflection": angular}
            )
            estimate = estimated_stl_triangles(design)
            if estimate > args.max_estimate:
                print(f"{name:<18} {linear:>7g} {angular:>7g} {estimate:>9} {'skipped':>9}")
                continue
            count, seconds = real_triangles(propeller.solid, linear, angular)
            ratios.append(estimate / count)
            print(
                f"{name:<18} {linear:>7g} {angular:>7g}"
                f" {estimate:>9} {count:>9} {estimate / count:>6.2f} "
                f"{seconds:>7.2f}",
                flush=True,
            )
    print(
        f"estimate / real: min {min(ratios):.2f}, max {max(ratios):.2f} over {len(ratios)} settings"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
