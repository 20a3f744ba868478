#!/usr/bin/env python3
"""Benchmark `torus-cad mesh` against the spec's PyVista route, and `torus-cad cfd`, on the default
design.

    python scripts/bench_mesh.py
        # 100 x 400 and 400 x 2000, PyVista at both, cfd: ~15-40 min
    python scripts/bench_mesh.py --quick      # 100 x 400 only (PyVista too), and cfd
    python scripts/bench_mesh.py --no-pyvista # torus-cad only

Never part of the test suite. Every run is a fresh process (a new Python, imports included),
timed from outside; its peak memory is the child's maximum resident set (``wait4``'s rusage).

- ``torus-cad mesh --sections S --points M`` (binary STL + the quality report): wall time, peak
  memory, triangles, closedness (open / non-manifold edges, from its report), stage times.
- The spec's route (§7) at the same sampling: each blade's structured grid (sections evenly in s,
  as the spec) triangulated and capped, the hub as the §6.2 structured grid with the same cell
  size, united one body at a time with PyVista's ``boolean_union``; then PyVista's ``clean`` and
  its count of open edges and manifoldness. PyVista's boolean can crash or run for hours, so it has
  a time limit (``--pyvista-timeout``).
- ``torus-cad cfd`` at the default sizes: wall and CPU time, peak memory, element counts, worst
  SICN.

Results go to ``bench_out/bench_mesh.json`` and a table on stdout.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from torus_cad.design.described_geometry import sampled_blade_surface

ROOT = Path(__file__).resolve().parent.parent


def run_measured(command: list[str], timeout: float) -> dict[str, Any]:
    """Run ``command``; wall seconds, the child's CPU seconds and peak RSS (MB), exit code, last
    stdout line."""
    start = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        process = subprocess.Popen(command, stdout=out, stderr=err, cwd=ROOT)
        deadline = start + timeout
        while True:
            pid, status, usage = os.wait4(process.pid, os.WNOHANG)
            if pid:
                break
            if time.perf_counter() > deadline:
                process.kill()
                _, status, usage = os.wait4(process.pid, 0)
                return {
                    "status": f"timed out after {timeout:g} s",
                    "wall_s": time.perf_counter() - start,
                    "peak_rss_mb": usage.ru_maxrss / 1024.0,
                }
            time.sleep(0.2)
        wall = time.perf_counter() - start
        out.seek(0)
        err.seek(0)
        lines = out.read().strip().splitlines()
        error = err.read().strip().splitlines()
    code = os.waitstatus_to_exitcode(status)
    return {
        "status": "ok" if code == 0 else f"exit code {code}: {(error or [''])[-1][:200]}",
        "wall_s": wall,
        "cpu_s": usage.ru_utime + usage.ru_stime,
        "peak_rss_mb": usage.ru_maxrss / 1024.0,
        "last_line": lines[-1] if lines else "",
    }


# -- torus-cad mesh
# -------------------------------------------------------------------------------------


def torus_cad_mesh(sections: int, points: int, timeout: float) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as folder:
        result = run_measured(
            [
                sys.executable,
                "-m",
                "torus_cad",
                "mesh",
                "--sections",
                str(sections),
                "--points",
                str(points),
                "--format",
                "stl",
                "--out",
                folder,
            ],
            timeout,
        )
        report_path = Path(folder) / "torus_propeller_mesh.json"
        if report_path.exists():
            report = json.loads(report_path.read_text())
            result.update(
                triangles=report["triangles"],
                topology=report["topology"],
                stage_seconds=report["stage_seconds"],
                volume_relative_difference=report.get("volume_relative_difference"),
                blade_edge_ratio=report["blades_away_from_junctions"]["edge_ratio"],
                opencascade_edge_ratio=report.get("opencascade_stl", {})
                .get("blades_away_from_junctions", {})
                .get("edge_ratio"),
                aspect_ratio_max=report["aspect_ratio_max"],
                aspect_ratio_max_blades_away=report["blades_away_from_junctions"][
                    "aspect_ratio_max"
                ],
                vertex_distance_max_mm=report["vertex_distance_max_mm"],
                cell_sag_max_mm=report["cell_sag_max_mm"],
                self_intersections=report["self_intersections"],
                self_intersection_scope=report["self_intersection_check"]["scope"],
            )
    return result


# -- the spec's PyVista route
# ------------------------------------------------------------------------------


def child_pyvista(sections: int, points: int) -> None:
    """Child process: the spec's §7 route with PyVista at ``sections`` x ``points``; prints one JSON
    line."""
    # this checkout's torus_cad, as `python -m torus_cad` from ROOT uses
    sys.path.insert(0, str(ROOT))
    import numpy as np
    import pyvista as pv

    from torus_cad.geometry.blade.triangle_mesh import blade_mesh
    from torus_cad.mesh.grids import cell_size, hub_mesh
    from torus_cad.parameters import PropellerParameters

    def polydata(vertices: np.ndarray, faces: np.ndarray) -> pv.PolyData:
        return pv.PolyData(
            np.asarray(vertices, float), np.hstack([np.full((len(faces), 1), 3), faces]).ravel()
        )

    params = PropellerParameters()
    start = time.perf_counter()
    surfaces = [
        sampled_blade_surface(params, index, sections, points) for index in range(params.blades)
    ]
    bodies = [
        polydata(*(lambda mesh: (mesh.vertices, mesh.faces))(blade_mesh(surface)))
        for surface in surfaces
    ]
    hub = hub_mesh(params.hub.radius, params.hub.length, cell_size(surfaces[0]).hub)
    result = polydata(hub.vertices, hub.faces)
    meshed = time.perf_counter()
    for body in bodies:
        result = result.boolean_union(body)
    union_s = time.perf_counter() - meshed
    cleaned = result.clean()
    print(
        json.dumps(
            {
                "triangles": int(result.n_cells),
                "open_edges": int(cleaned.n_open_edges),
                "manifold": bool(cleaned.is_manifold),
                "mesh_s": meshed - start,
                "union_s": union_s,
                "volume_mm3": float(cleaned.volume),
            }
        )
    )


def pyvista_route(sections: int, points: int, timeout: float) -> dict[str, Any]:
    result = run_measured(
        [sys.executable, __file__, "--child-pyvista", str(sections), str(points)], timeout
    )
    if result["status"] == "ok" and result["last_line"].startswith("{"):
        result.update(json.loads(result["last_line"]))
        result["closed"] = result["open_edges"] == 0 and result["manifold"]
    return result


# -- volume convergence
# -------------------------------------------------------------------------------------


def convergence(levels: int) -> list[dict[str, Any]]:
    """Volume of the mesh against the B-rep's as both counts double from 24 x 48 (in this
    process)."""
    sys.path.insert(0, str(ROOT))
    import numpy as np

    from torus_cad.kernel.mass_properties import precise_volume
    from torus_cad.mesh.pipeline import build_surface_mesh
    from torus_cad.parameters import PropellerParameters
    from torus_cad.propeller import build_propeller

    brep = precise_volume(build_propeller(PropellerParameters()).solid)
    rows: list[dict[str, Any]] = []
    for level in range(levels):
        sections, points = 24 * 2**level, 48 * 2**level
        params = PropellerParameters().with_values(
            {"mesh.sections": sections, "mesh.points": points}
        )
        mesh = build_surface_mesh(params).mesh
        error = mesh.triangle_mesh.volume / brep - 1.0
        row = {
            "sections": sections,
            "points": points,
            "triangles": len(mesh.faces),
            "relative_error": error,
        }
        if rows:
            row["order"] = float(np.log2(abs(rows[-1]["relative_error"]) / abs(error)))
        rows.append(row)
        print(
            f"  {sections:4d} x {points:5d}: {len(mesh.faces):>9,}"
            f" triangles, volume {error:+.3e} of the B-rep's"
            + (f", order {row['order']:.2f}" if "order" in row else ""),
            flush=True,
        )
    return rows


# -- torus-cad cfd
# ----------------------------------------------------------------------------------------


def torus_cad_cfd(timeout: float) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as folder:
        result = run_measured([sys.executable, "-m", "torus_cad", "cfd", "--out", folder], timeout)
        report_path = Path(folder) / "torus_propeller_cfd.json"
        if report_path.exists():
            report = json.loads(report_path.read_text())
            result.update(
                {
                    key: report[key]
                    for key in (
                        "tetrahedra",
                        "tetrahedra_total",
                        "triangles",
                        "nodes",
                        "sicn_min",
                        "sicn_mean",
                        "stage_seconds",
                        "volume_relative_difference",
                        "wall_seconds",
                    )
                }
            )
    return result


# -- report
# -----------------------------------------------------------------------------------------------


def _mb(value: float | None) -> str:
    return "-" if value is None else f"{value:,.0f}"


def print_report(report: dict[str, Any]) -> None:
    print(
        f"\n== Surface meshes of the default design ({report['machine']['cores']} cores, "
        f"load average {report['machine']['load_average']}) =="
    )
    print(
        f"  {'route':<28}{'sampling':>12}{'wall s':>9}"
        f"{'cpu s':>8}{'peak MB':>9}{'triangles':>12}  closed"
    )
    for row in report["mesh"]:
        label = f"{row['sections']} x {row['points']}"
        for route in ("torus_cad", "pyvista"):
            result = row.get(route)
            if result is None:
                continue
            name = "torus-cad mesh (manifold3d)" if route == "torus_cad" else "spec route (PyVista)"
            if result["status"] != "ok":
                print(
                    f"  {name:<28}{label:>12}{result['wall_s']:9.1f}"
                    f"{'':>8}{_mb(result.get('peak_rss_mb')):>9}"
                    f"{'':>12}  {result['status']}"
                )
                continue
            if route == "torus_cad":
                topology = result["topology"]
                closed = (
                    "yes (0 open, 0 non-manifold)"
                    if topology["closed_2_manifold"]
                    else (
                        f"NO ({topology['open_edges']} open, "
                        f"{topology['non_manifold_edges']} non-manifold)"
                    )
                )
                closed += (
                    f", {result['self_intersections']} intersecting "
                    f"pairs ({result['self_intersection_scope']})"
                )
            else:
                closed = "yes" if result["closed"] else f"NO ({result['open_edges']} open edges)"
            print(
                f"  {name:<28}{label:>12}{result['wall_s']:9.1f}{result['cpu_s']:8.1f}"
                f"{_mb(result['peak_rss_mb']):>9}{result['triangles']:>12,}  {closed}"
            )
        if row.get("torus_cad", {}).get("status") == "ok":
            result = row["torus_cad"]
            stages = ", ".join(
                f"{key} {value:.1f}" for key, value in result["stage_seconds"].items()
            )
            print(
                f"    torus-cad stages (s): {stages}; volume vs "
                f"B-rep {result['volume_relative_difference']:+.4%}; "
                f"blade edge ratio {result['blade_edge_ratio']:.1f} (OpenCascade STL "
                f"{result['opencascade_edge_ratio']:.1f}); "
                f"worst aspect {result['aspect_ratio_max']:.3g} "
                f"({result['aspect_ratio_max_blades_away']:.1f} on the blades away from the hub)"
            )
    cfd = report.get("cfd")
    if cfd:
        print("\n== torus-cad cfd, default sizes ==")
        if cfd["status"] != "ok":
            print(f"  {cfd['status']}")
            return
        print(
            f"  wall {cfd['wall_s']:.1f} s (process), cpu "
            f"{cfd['cpu_s']:.1f} s, peak {cfd['peak_rss_mb']:.0f} MB; "
            f"{cfd['tetrahedra_total']:,} tetrahedra "
            f"({cfd['tetrahedra']}), {cfd['nodes']:,} nodes; "
            f"worst SICN {cfd['sicn_min']:.3f}, mean {cfd['sicn_mean']:.3f}"
        )
        print(
            "  stages (s): "
            + ", ".join(f"{key} {value:.1f}" for key, value in cfd["stage_seconds"].items())
        )
        print(f"  meshed volumes vs exact: {cfd['volume_relative_difference']}")


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--quick", action="store_true", help="100 x 400 only")
    parser.add_argument("--no-pyvista", action="store_true", help="skip the spec's PyVista route")
    parser.add_argument("--no-cfd", action="store_true", help="skip torus-cad cfd")
    parser.add_argument(
        "--convergence",
        type=int,
        default=0,
        metavar="LEVELS",
        help="only the volume convergence study: 24 x 48 doubled LEVELS - 1 times",
    )
    parser.add_argument(
        "--pyvista-timeout", type=float, default=1800.0, help="seconds per PyVista run"
    )
    parser.add_argument("--child-pyvista", nargs=2, type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child_pyvista:
        child_pyvista(*args.child_pyvista)
        return
    if args.convergence:
        print("volume of the mesh against the B-rep's, default design, arc-length spacing:")
        convergence(args.convergence)
        return
    samplings = [(100, 400)] if args.quick else [(100, 400), (400, 2000)]
    report: dict[str, Any] = {
        "machine": {
            "cores": os.cpu_count(),
            "python": platform.python_version(),
            "load_average": " ".join(f"{x:.1f}" for x in os.getloadavg()),
        },
        "mesh": [],
    }
    for sections, points in samplings:
        row: dict[str, Any] = {"sections": sections, "points": points}
        print(f"torus-cad mesh {sections} x {points} ...", flush=True)
        row["torus_cad"] = torus_cad_mesh(sections, points, timeout=3600.0)
        if not args.no_pyvista:
            print(f"PyVista route {sections} x {points} ...", flush=True)
            row["pyvista"] = pyvista_route(sections, points, args.pyvista_timeout)
        report["mesh"].append(row)
    if not args.no_cfd:
        print("torus-cad cfd (default sizes) ...", flush=True)
        report["cfd"] = torus_cad_cfd(timeout=1800.0)
    report["machine"]["load_average_end"] = " ".join(f"{x:.1f}" for x in os.getloadavg())
    out = ROOT / "bench_out"
    out.mkdir(exist_ok=True)
    (out / "bench_mesh.json").write_text(json.dumps(report, indent=2) + "\n")
    print_report(report)
    print(f"\nJSON: {out / 'bench_mesh.json'}")


if __name__ == "__main__":
    main()
