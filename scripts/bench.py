#!/usr/bin/env python3
"""Benchmark the generator: stage times, scaling, and the spec's mesh-boolean route side by side.

    python scripts/bench.py
        # full run, a few minutes; table + bench_out/bench.json
    python scripts/bench.py --runs 3 --quick   # fewer runs and scaling points

Never part of the test suite. Sections of the report:

1. Stage times of the default propeller, median of ``--runs`` in-process runs after a
   warm-up: parameters, section math (incl. the pre-kernel checks), wires, loft, fuse,
   validity check, STEP write, STL write (and the JSON report, which integrates mass
   properties). Also the cold command-line wall time (``torus-cad build``, new process).
2. Scaling: sections 10 -> 100, points 40 -> 400, blades 1 -> 8, one subprocess per
   configuration (time of a second, warm build, and peak memory); which stage dominates and
   its growth exponent (slope of log time against log size).
3. The spec's own route (§7): triangulate each body's structured mesh and boolean-union the
   meshes with PyVista, at the same sampling as the B-rep; as the spec writes it (PyVista's
   triangulated Cylinder hub) and with a structured hub grid (spec §6.2); plus manifold3d,
   a robust mesh boolean, for comparison. Time, closed-manifold or not, triangles.
4. Accuracy of each route against the analytic surface: distance from surface samples half
   way between sections (away from the hub) to the result.
5. Mass properties and balance: the fast route (blade faces alone) against BRepGProp at 1e-6
   and 1e-4 (the old route), CPU time on the default; both routes' mass properties against
   BRepGProp at 1e-9 on the default and ``--mass-designs`` random designs.

The mesh routes run in subprocesses: PyVista's boolean can crash the interpreter.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface

STAGES = ("parameters", "section_math", "wires", "loft", "fuse", "check", "step_write", "stl_write")
BUILD_STAGES = STAGES[:6]

#: A narrow-span variant of the default whose blades clear each other for 1..8 blades
#: (the default's 100 degree span only fits 3), used for the blade-count scaling.
NARROW = {
    "centerline.p2": [10.0, 3.0, 22.0],
    "centerline.p3": [30.0, 15.0, 22.0],
    "centerline.p4": [40.0, 18.0],
    "transforms.scale_x": [0.0, 0.0, -4.0, 4.0, 3.0],
    "transforms.scale_y": [0.0, 0.0, -2.0, 2.0, 1.5],
}

TARGETS = {"step_s": 1.0, "step_stl_s": 2.0, "speedup": 5.0}


# -- helpers -----------------------------------------------------------------------------------


def _params(changes: dict[str, Any] | None = None):
    from torus_cad.parameters import PropellerParameters

    return PropellerParameters().with_values(changes or {})


def _median(values: list[float]) -> float:
    return float(statistics.median(values)) if values else float("nan")


def _run_child(mode: str, payload: dict[str, Any], timeout: float = 600.0) -> dict[str, Any]:
    """Run this script in a child process in ``mode``; its last stdout line is a JSON result."""
    command = [sys.executable, __file__, f"--child-{mode}", json.dumps(payload)]
    start = time.perf_counter()
    try:
        result = subprocess.run(command, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"status": f"timed out after {timeout:g} s", "wall_s": time.perf_counter() - start}
    if result.returncode != 0:
        signal_name = ""
        if result.returncode < 0:
            import signal

            signal_name = f" ({signal.Signals(-result.returncode).name})"
        tail = (result.stderr.strip().splitlines() or [""])[-1][:200]
        return {
            "status": f"crashed: exit code {result.returncode}{signal_name}",
            "stderr": tail,
            "wall_s": time.perf_counter() - start,
        }
    lines = [line for line in result.stdout.strip().splitlines() if line.startswith("{")]
    return (
        json.loads(lines[-1])
        if lines
        else {"status": "no result", "wall_s": time.perf_counter() - start}
    )


def _maxrss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _rss_mb() -> float:
    with open("/proc/self/statm") as handle:
        return int(handle.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


# -- 1. stage times ------------------------------------------------------------------------------


def timed_build_and_write(params, out_dir: Path) -> dict[str, float]:
    """One build plus STEP and STL writes (the JSON report separately); seconds per stage."""
    from torus_cad.kernel.writers.step import write_step
    from torus_cad.kernel.writers.stl import write_stl
    from torus_cad.outputs.build_report import build_report
    from torus_cad.propeller import build_propeller

    start = time.perf_counter()
    propeller = build_propeller(params)
    seconds = dict(propeller.stage_seconds)
    seconds["build_total"] = time.perf_counter() - start
    t0 = time.perf_counter()
    write_step(
        propeller.solid, out_dir / f"{params.name}.step", params.name, params.export.step_schema
    )
    seconds["step_write"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    write_stl(
        propeller.solid,
        out_dir / f"{params.name}.stl",
        params.export.stl_linear_deflection,
        params.export.stl_angular_deflection,
    )
    seconds["stl_write"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    build_report(propeller, 1.24)
    seconds["json_report"] = time.perf_counter() - t0
    seconds["step_total"] = seconds["build_total"] + seconds["step_write"]
    seconds["step_stl_total"] = seconds["step_total"] + seconds["stl_write"]
    return seconds


def stage_times(runs: int) -> dict[str, Any]:
    params = _params()
    with tempfile.TemporaryDirectory() as folder:
        timed_build_and_write(params, Path(folder))  # warm-up: imports, caches
        samples = [timed_build_and_write(params, Path(folder)) for _ in range(runs)]
        step_bytes = (Path(folder) / f"{params.name}.step").stat().st_size
        stl_bytes = (Path(folder) / f"{params.name}.stl").stat().st_size
    keys = samples[0].keys()
    median = {key: _median([sample[key] for sample in samples]) for key in keys}
    spread = {
        key: (min(sample[key] for sample in samples), max(sample[key] for sample in samples))
        for key in keys
    }
    return {
        "runs": runs,
        "median_s": median,
        "min_max_s": spread,
        "step_bytes": step_bytes,
        "stl_triangles": (stl_bytes - 84) // 50,
    }


#: The workshop scenario: the default with a bore, D-flat, set screw, chamfer, a 0.3 mm
#: blunt trailing edge (round, the default shape) and a 0.5 mm root fillet. The chamfer is 0.2 mm:
#: the default's blade root comes within 0.85 mm of the hub's end, and a chamfer may not reach the
#: fillet's spread (2 radii) over the hub.
WORKSHOP_CHANGES = {
    "hub.bore_diameter": 5.0,
    "hub.bore_flat_depth": 0.5,
    "hub.set_screw_diameter": 3.0,
    "hub.chamfer": 0.2,
    "airfoil.trailing_edge_thickness": 0.3,
    "hub.root_fillet_radius": 0.5,
}


def workshop_stage_times(runs: int) -> dict[str, Any]:
    """Stage times of the workshop scenario, build to a valid STEP (median of ``runs`` warm
    runs)."""
    params = _params(WORKSHOP_CHANGES)
    with tempfile.TemporaryDirectory() as folder:
        timed_build_and_write(params, Path(folder))  # warm-up
        samples = [timed_build_and_write(params, Path(folder)) for _ in range(runs)]
    keys = samples[0].keys()
    return {
        "runs": runs,
        "changes": WORKSHOP_CHANGES,
        "median_s": {key: _median([sample[key] for sample in samples]) for key in keys},
    }


def cli_wall_time(runs: int) -> dict[str, Any]:
    """Cold `torus-cad build` of the default, new process each time (imports included)."""
    times = []
    with tempfile.TemporaryDirectory() as folder:
        for _ in range(runs):
            start = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "torus_cad", "build", "--out", folder, "-q"], check=True
            )
            times.append(time.perf_counter() - start)
        times_no_stl = []
        for _ in range(runs):
            start = time.perf_counter()
            subprocess.run(
                [sys.executable, "-m", "torus_cad", "build", "--out", folder, "-q", "--no-stl"],
                check=True,
            )
            times_no_stl.append(time.perf_counter() - start)
    start = time.perf_counter()
    subprocess.run([sys.executable, "-c", "import cadquery, torus_cad.propeller"], check=True)
    import_s = time.perf_counter() - start
    return {
        "runs": runs,
        "build_median_s": _median(times),
        "build_no_stl_median_s": _median(times_no_stl),
        "python_and_imports_s": import_s,
    }


# -- 2. scaling ------------------------------------------------------------------------------------


def child_scaling(payload: dict[str, Any]) -> dict[str, Any]:
    """Child: build twice (the second is timed), write STEP + STL; report stage times and memory."""
    import torus_cad.propeller  # noqa: F401 - imports before the memory baseline
    from torus_cad.errors import TorusCadError

    baseline = _rss_mb()
    try:
        params = _params(payload["changes"])
        with tempfile.TemporaryDirectory() as folder:
            timed_build_and_write(params, Path(folder))
            seconds = timed_build_and_write(params, Path(folder))
    except TorusCadError as error:
        return {"status": f"{type(error).__name__}: {error}"}
    return {
        "status": "ok",
        "seconds": seconds,
        "baseline_rss_mb": baseline,
        "peak_rss_mb": _maxrss_mb(),
    }


def scaling(quick: bool) -> dict[str, Any]:
    axes = {
        "sections": [10, 25, 50, 100] if not quick else [10, 50],
        "points": [40, 80, 160, 400] if not quick else [40, 160],
        "blades": [1, 2, 3, 4, 6, 8] if not quick else [1, 4, 8],
    }
    results: dict[str, Any] = {}
    for axis, values in axes.items():
        rows = []
        for value in values:
            changes: dict[str, Any] = {
                f"resolution.{axis}" if axis != "blades" else "blades": value
            }
            if axis == "blades":
                changes.update(NARROW)
            result = _run_child("scaling", {"changes": changes})
            result["value"] = value
            rows.append(result)
            print(
                f"  scaling {axis:<8} {value:4d}: "
                + (
                    f"build {result['seconds']['build_total']:.3f} s, "
                    f"fuse {result['seconds']['fuse']:.3f} s, "
                    f"peak {result['peak_rss_mb']:.0f} MB"
                    if result.get("status") == "ok"
                    else result["status"]
                ),
                flush=True,
            )
        results[axis] = {"rows": rows, "analysis": _growth(rows)}
    return results


def _growth(rows: list[dict[str, Any]]) -> dict[str, Any]:
    good = [row for row in rows if row.get("status") == "ok"]
    if len(good) < 2:
        return {}
    largest = good[-1]["seconds"]
    dominant = max(STAGES, key=lambda stage: largest.get(stage, 0.0))
    x = np.log([row["value"] for row in good])
    exponents = {}
    for stage in (*STAGES, "build_total"):
        y = np.log([max(row["seconds"].get(stage, 0.0), 1e-6) for row in good])
        exponents[stage] = float(np.polyfit(x, y, 1)[0])
    memory = np.log([max(row["peak_rss_mb"] - row["baseline_rss_mb"], 1e-3) for row in good])
    return {
        "dominant_stage": dominant,
        "dominant_share": largest[dominant] / largest["step_stl_total"],
        "exponents": exponents,
        "memory_exponent": float(np.polyfit(x, memory, 1)[0]),
    }


# -- 3 + 4. the mesh-boolean route and accuracy --------------------------------------------------


def accuracy_samples(params, per_gap: int = 3, limit: int = 400) -> np.ndarray:
    """Analytic surface points at s half-way between sections and t between samples, away from the
    hub."""
    from torus_cad.geometry.blade.blade_surface import surface_points

    surface = sampled_blade_surface(params)
    s = 0.5 * (surface.s[:-1] + surface.s[1:])
    t = np.sort(np.concatenate([surface.t, 0.5 * (surface.t[:-1] + surface.t[1:])]))[::per_gap]
    points = surface_points(
        propeller_geometry(params).blade, propeller_geometry(params).centerline(), s, t
    ).reshape(-1, 3)
    margin = 0.05 * params.hub.radius
    away = (np.hypot(points[:, 0], points[:, 1]) > params.hub.radius + margin) | (
        np.abs(points[:, 2]) > params.hub.length / 2 + margin
    )
    points = points[away]
    if len(points) > limit:
        points = points[np.linspace(0, len(points) - 1, limit).astype(int)]
    return points


def _chord(params) -> float:
    from torus_cad.geometry.blade.transforms import evaluate_quartic

    return float(np.min(evaluate_quartic(params.transforms.scale_x, np.linspace(0, 1, 101))))


def hub_grid_mesh(radius: float, length: float, around: int, along: int, rings: int):
    """Spec §6.2 hub as a structured grid: ``around`` x ``along`` on the side, caps of ``rings``
    rings."""
    theta = np.linspace(0.0, 2.0 * np.pi, around, endpoint=False)
    cap_radii = np.linspace(radius, 0.0, rings + 1)[:-1]
    loops = (
        [(r, -length / 2) for r in cap_radii[::-1]]
        + [(radius, z) for z in np.linspace(-length / 2, length / 2, along)[1:-1]]
        + [(r, length / 2) for r in cap_radii]
    )
    vertices = [
        np.stack([r * np.cos(theta), r * np.sin(theta), np.full(around, z)], -1) for r, z in loops
    ]
    vertices = np.concatenate(
        vertices + [np.array([[0.0, 0.0, -length / 2], [0.0, 0.0, length / 2]])]
    )
    j = np.arange(around)
    following = (j + 1) % around
    faces = []
    for k in range(len(loops) - 1):
        a, b = k * around + j, k * around + following
        faces += [np.stack([a, b, b + around], -1), np.stack([a, b + around, a + around], -1)]
    bottom, top, last = len(loops) * around, len(loops) * around + 1, (len(loops) - 1) * around
    faces += [
        np.stack([np.full(around, bottom), following, j], -1),
        np.stack([np.full(around, top), last + j, last + following], -1),
    ]
    return vertices, np.concatenate(faces)


def _polydata(vertices: np.ndarray, faces: np.ndarray):
    import pyvista as pv

    return pv.PolyData(
        np.asarray(vertices, float), np.hstack([np.full((len(faces), 1), 3), faces]).ravel()
    )


def child_mesh_route(payload: dict[str, Any]) -> dict[str, Any]:
    """Child: the mesh-boolean route on the default (or ``changes``), timed; closedness and
    accuracy."""
    import pyvista as pv

    from torus_cad.geometry.blade.triangle_mesh import blade_mesh

    params = _params(payload.get("changes"))
    variant = payload["variant"]
    start = time.perf_counter()
    blades = [blade_mesh(sampled_blade_surface(params, index)) for index in range(params.blades)]
    if variant in ("pyvista_spec", "pyvista_grid"):
        bodies = [_polydata(mesh.vertices, mesh.faces) for mesh in blades]
        if variant == "pyvista_spec":
            hub = (
                pv.Cylinder(
                    center=(0, 0, 0),
                    direction=(0, 0, 1),
                    radius=params.hub.radius,
                    height=params.hub.length,
                    resolution=params.resolution.points,
                )
                .triangulate()
                .clean()
            )
        else:
            hub = _polydata(
                *hub_grid_mesh(
                    params.hub.radius,
                    params.hub.length,
                    params.resolution.points,
                    params.resolution.sections,
                    5,
                )
            )
        meshed = time.perf_counter()
        result = hub
        for body in bodies:
            result = result.boolean_union(body)
        union_s = time.perf_counter() - meshed
        cleaned = result.clean()
        closed = bool(cleaned.is_manifold) and cleaned.n_open_edges == 0
        open_edges = int(cleaned.n_open_edges)
        triangles = int(result.n_cells)
        volume = float(cleaned.volume)
    elif variant == "manifold3d":
        import manifold3d as mf

        bodies = [
            mf.Manifold(
                mf.Mesh(
                    vert_properties=mesh.vertices.astype(np.float32),
                    tri_verts=mesh.faces.astype(np.uint32),
                )
            )
            for mesh in blades
        ]
        vertices, faces = hub_grid_mesh(
            params.hub.radius,
            params.hub.length,
            params.resolution.points,
            params.resolution.sections,
            5,
        )
        hub = mf.Manifold(
            mf.Mesh(vert_properties=vertices.astype(np.float32), tri_verts=faces.astype(np.uint32))
        )
        meshed = time.perf_counter()
        union = mf.Manifold.batch_boolean([hub, *bodies], mf.OpType.Add)
        out = union.to_mesh()
        union_s = time.perf_counter() - meshed
        result = _polydata(
            np.asarray(out.vert_properties)[:, :3], np.asarray(out.tri_verts, dtype=np.int64)
        )
        closed = (
            union.status() == mf.Error.NoError
            and result.n_open_edges == 0
            and bool(result.is_manifold)
        )
        open_edges = int(result.n_open_edges)
        triangles = int(union.num_tri())
        volume = float(union.volume())
    else:
        raise ValueError(variant)
    total_s = time.perf_counter() - start
    samples = accuracy_samples(params)
    _, closest = result.find_closest_cell(samples, return_closest_point=True)
    distances = np.linalg.norm(closest - samples, axis=1)
    return {
        "status": "ok",
        "variant": variant,
        "total_s": total_s,
        "mesh_s": meshed - start,
        "union_s": union_s,
        "closed_manifold": closed,
        "open_edges": open_edges,
        "triangles": triangles,
        "volume_mm3": volume,
        "distance_max_mm": float(distances.max()),
        "distance_mean_mm": float(distances.mean()),
        "distance_max_rel_chord": float(distances.max() / _chord(params)),
        "samples": len(samples),
    }


def brep_accuracy(params) -> dict[str, Any]:
    from torus_cad.kernel.checks import distances_to_shape
    from torus_cad.kernel.mass_properties import precise_volume
    from torus_cad.propeller import build_propeller

    propeller = build_propeller(params)
    samples = accuracy_samples(params)
    distances = distances_to_shape(propeller.solid, samples)
    return {
        "distance_max_mm": float(distances.max()),
        "distance_mean_mm": float(distances.mean()),
        "distance_max_rel_chord": float(distances.max() / _chord(params)),
        "samples": len(samples),
        "volume_mm3": precise_volume(propeller.solid),
        "closed_manifold": True,
    }


def mesh_route(runs: int) -> dict[str, Any]:
    """B-rep and mesh routes interleaved, ``runs`` times each, on the default at equal sampling."""
    from torus_cad.propeller import build_propeller

    params = _params()
    build_propeller(params)  # warm
    variants = ("pyvista_spec", "pyvista_grid", "manifold3d")
    brep_times: list[float] = []
    mesh: dict[str, list[dict[str, Any]]] = {variant: [] for variant in variants}
    for _ in range(runs):
        start = time.perf_counter()
        build_propeller(params)
        brep_times.append(time.perf_counter() - start)
        for variant in variants:
            mesh[variant].append(_run_child("mesh", {"variant": variant}, timeout=300))
    summary: dict[str, Any] = {
        "sampling": {
            "sections": params.resolution.sections,
            "points": params.resolution.points,
            "blades": params.blades,
        },
        "brep": {"total_s": _median(brep_times), **brep_accuracy(params)},
    }
    for variant, results in mesh.items():
        good = [result for result in results if result.get("status") == "ok"]
        if not good:
            summary[variant] = {"status": results[0].get("status", "failed"), "runs": len(results)}
            continue
        row = dict(good[-1])
        row["total_s"] = _median([result["total_s"] for result in good])
        row["union_s"] = _median([result["union_s"] for result in good])
        row["runs_ok"] = len(good)
        row["runs"] = len(results)
        if len(good) < len(results):
            row["failures"] = sorted(
                {result["status"] for result in results if result.get("status") != "ok"}
            )
        row["speedup_of_brep"] = row["total_s"] / summary["brep"]["total_s"]
        summary[variant] = row
    return summary


# -- 5. mass properties
# -------------------------------------------------------------------------------


def mass_properties_bench(runs: int, designs: int) -> dict[str, Any]:
    """The JSON report's mass properties and balance: the fast route (blade faces alone) against
    the old route (BRepGProp at 1e-6 for the mass properties, 1e-4 for the balance), CPU seconds
    on the default (median of ``runs``); and the mass properties of both routes against BRepGProp
    at 1e-9 on the default and ``designs`` random designs (worst relative errors)."""
    import torus_cad.kernel.blade_integrals as blade_integrals
    from torus_cad.errors import GeometryError, ParameterError
    from torus_cad.kernel.mass_properties import (
        balance,
        balance_of,
        mass_properties,
        occt_mass_properties,
        volume_properties,
    )
    from torus_cad.propeller import build_propeller

    # studies/ sits beside torus_cad, outside it
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
    from studies.fuzz import random_design
    from torus_cad.tolerances import BALANCE_RELATIVE_PRECISION

    def fast(solid) -> Any:
        blade_integrals._LAST[0] = (None, 0, None)  # no answer kept from an earlier call
        return mass_properties(solid, 1.0), balance(solid, 1.0)

    def old(solid) -> Any:
        return (
            occt_mass_properties(solid, 1.0),
            balance_of(volume_properties(solid, BALANCE_RELATIVE_PRECISION), 1.0),
        )

    def cpu_seconds(function, solid) -> tuple[float, Any]:
        start = time.process_time()
        result = function(solid)
        return time.process_time() - start, result

    default = build_propeller(_params())
    fast_s = [cpu_seconds(fast, default.solid)[0] for _ in range(runs)]
    old_s = [cpu_seconds(old, default.solid)[0] for _ in range(runs)]
    keys = ("volume", "area", "inertia", "centroid", "box")
    worst = {"fast": dict.fromkeys(keys, 0.0), "old": dict.fromkeys(keys, 0.0)}
    ratios, fast_route, seed, checked = [], 0, 0, [default]
    while len(checked) < designs + 1:
        seed += 1
        try:
            checked.append(build_propeller(random_design(seed)))
        except (ParameterError, GeometryError):
            continue
    for propeller in checked:
        reference = occt_mass_properties(propeller.solid, 1.0, 1e-9)
        size = float(np.linalg.norm(np.subtract(*reference.bounding_box_mm)))
        seconds = {}
        for route, function in (("fast", fast), ("old", old)):
            seconds[route], (got, _) = cpu_seconds(function, propeller.solid)
            errors = {
                "volume": abs(got.volume_mm3 / reference.volume_mm3 - 1.0),
                "area": abs(got.surface_area_mm2 / reference.surface_area_mm2 - 1.0),
                "inertia": abs(got.spin_axis_inertia_mm5 / reference.spin_axis_inertia_mm5 - 1.0),
                "centroid": float(np.abs(np.subtract(got.centroid_mm, reference.centroid_mm)).max())
                / size,
                "box": float(
                    np.abs(np.subtract(got.bounding_box_mm, reference.bounding_box_mm)).max()
                )
                / size,
            }
            worst[route] = {key: max(worst[route][key], value) for key, value in errors.items()}
        fast_route += blade_integrals.hub_with_blade_integrals(propeller.solid.wrapped) is not None
        ratios.append(seconds["old"] / seconds["fast"])
    return {
        "runs": runs,
        "default_fast_cpu_s": _median(fast_s),
        "default_old_cpu_s": _median(old_s),
        "speedup": _median(old_s) / _median(fast_s),
        "designs": len(checked),
        "fast_route_taken": fast_route,
        "speedup_median_over_designs": _median(ratios),
        "speedup_min_over_designs": min(ratios),
        "worst_relative_error": worst,
    }


# -- report
# --------------------------------------------------------------------------------------------


def print_report(report: dict[str, Any]) -> None:
    stages = report["stage_times"]
    median = stages["median_s"]
    print()
    print(
        f"== Stage times, default propeller (median of {stages['runs']} warm runs, "
        f"{report['machine']['cores']} cores) =="
    )
    print(f"  {'stage':<14}{'median ms':>10}{'min-max ms':>18}")
    for stage in (*STAGES, "json_report"):
        low, high = stages["min_max_s"][stage]
        print(f"  {stage:<14}{median[stage] * 1e3:10.1f}{f'{low * 1e3:.0f}-{high * 1e3:.0f}':>18}")
    step_ok = median["step_total"] <= TARGETS["step_s"]
    both_ok = median["step_stl_total"] <= TARGETS["step_stl_s"]
    print(
        f"  valid solid -> STEP    {median['step_total']:.3f} s  "
        f"(target <= {TARGETS['step_s']:g} s: "
        f"{'met' if step_ok else 'MISSED'})"
    )
    print(
        f"  valid solid -> STEP+STL {median['step_stl_total']:.3f} s  "
        f"(target <= {TARGETS['step_stl_s']:g} s: "
        f"{'met' if both_ok else 'MISSED'})"
    )
    print(f"  STL {stages['stl_triangles']} triangles, STEP {stages['step_bytes'] / 1024:.0f} KiB")
    if "cli" in report:
        cli = report["cli"]
        print(
            f"  cold CLI 'torus-cad build' (new process): {cli['build_median_s']:.2f} s with STL, "
            f"{cli['build_no_stl_median_s']:.2f} s without; of which "
            f"Python + imports {cli['python_and_imports_s']:.2f} s"
        )

    if "scaling" in report:
        print()
        print("== Scaling (one subprocess per row; second, warm build; peak RSS of the process) ==")
        header = "".join(
            f"{name:>9}" for name in ("sec.math", "wires", "loft", "fuse", "check", "step", "stl")
        )
        print(f"  {'axis':<9}{'value':>6}{header}{'total s':>9}{'peak MB':>9}")
        for axis, block in report["scaling"].items():
            for row in block["rows"]:
                if row.get("status") != "ok":
                    print(f"  {axis:<9}{row['value']:>6}  {str(row.get('status'))[:110]}")
                    continue
                s = row["seconds"]
                cells = "".join(
                    f"{s[stage]:9.3f}"
                    for stage in (
                        "section_math",
                        "wires",
                        "loft",
                        "fuse",
                        "check",
                        "step_write",
                        "stl_write",
                    )
                )
                print(
                    f"  {axis:<9}{row['value']:>6}{cells}"
                    f"{s['step_stl_total']:9.3f}{row['peak_rss_mb']:9.0f}"
                )
            analysis = block["analysis"]
            if analysis:
                dominant = analysis["dominant_stage"]
                print(
                    f"    -> {dominant} dominates "
                    f"({analysis['dominant_share']:.0%} of the largest case); "
                    f"it grows ~ {axis}^{analysis['exponents'][dominant]:.2f}, the whole build "
                    f"~ {axis}^{analysis['exponents']['build_total']:.2f}, "
                    f"memory ~ {axis}^{analysis['memory_exponent']:.2f}"
                )

    if "mesh_route" in report:
        route = report["mesh_route"]
        sampling = route["sampling"]
        print()
        print(
            "== B-rep vs the spec's mesh-boolean route (§7), "
            f"equal sampling: {sampling['sections']} sections x "
            f"{sampling['points']} points, {sampling['blades']} blades =="
        )
        print(
            f"  {'route':<40}{'time s':>8}{'B-rep faster':>13}{'closed':>8}{'open edges':>11}"
            f"{'max dist mm':>12}{'mean dist mm':>13}"
        )
        brep = route["brep"]
        print(
            f"  {'B-rep (loft, shared-intersection fuse)':<40}"
            f"{brep['total_s']:8.3f}{'':>13}{'yes':>8}{0:>11}"
            f"{brep['distance_max_mm']:12.5f}{brep['distance_mean_mm']:13.5f}"
        )
        labels = {
            "pyvista_spec": "PyVista, spec as written (Cylinder hub)",
            "pyvista_grid": "PyVista, structured hub grid (§6.2)",
            "manifold3d": "manifold3d (robust mesh boolean)",
        }
        for variant, label in labels.items():
            row = route.get(variant, {})
            if row.get("status") != "ok":
                print(
                    f"  {label:<40}  {row.get('status', 'not run')} ("
                    f"{row.get('runs', 0)} of {row.get('runs', 0)} runs)"
                )
                continue
            note = (
                f"  [{row['runs_ok']}/{row['runs']} runs ok: {', '.join(row['failures'])}]"
                if row.get("failures")
                else ""
            )
            print(
                f"  {label:<40}{row['total_s']:8.3f}{row['speedup_of_brep']:12.1f}"
                f"x{'yes' if row['closed_manifold'] else 'NO':>8}"
                f"{row['open_edges']:>11}{row['distance_max_mm']:12.5f}"
                f"{row['distance_mean_mm']:13.5f}{note}"
            )
        chord = (
            brep["distance_max_mm"] / brep["distance_max_rel_chord"]
            if brep["distance_max_rel_chord"]
            else float("nan")
        )
        print(
            f"  accuracy: {brep['samples']} analytic surface "
            "points half-way between sections, away from the hub; "
            f"smallest chord {chord:.2f} mm"
        )
        grid = route.get("pyvista_grid", {})
        if grid.get("status") == "ok":
            met = grid["speedup_of_brep"] >= TARGETS["speedup"]
            print(
                f"  target: B-rep >= {TARGETS['speedup']:g}x faster than the PyVista route: "
                f"{grid['speedup_of_brep']:.1f}x ({'met' if met else 'MISSED'})"
            )

    if "mass_properties" in report:
        mass = report["mass_properties"]
        print()
        print(
            f"== Mass properties and balance (JSON report; CPU time, median of {mass['runs']}) =="
        )
        print(
            f"  {'mass_properties':<14}"
            f"{mass['default_fast_cpu_s'] * 1e3:10.1f} ms  blade faces alone "
            f"(old route, BRepGProp 1e-6 and 1e-4: {mass['default_old_cpu_s'] * 1e3:.0f} ms; "
            f"{mass['speedup']:.1f}x faster, target >= 4x: "
            f"{'met' if mass['speedup'] >= 4.0 else 'MISSED'})"
        )
        print(
            f"  {mass['designs']} designs (default + random): "
            f"fast route taken by {mass['fast_route_taken']}, "
            f"speed-up median {mass['speedup_median_over_designs']:.1f}x, "
            f"min {mass['speedup_min_over_designs']:.1f}x"
        )
        for route, label in (("fast", "fast route"), ("old", "BRepGProp 1e-6")):
            errors = mass["worst_relative_error"][route]
            print(
                f"  worst vs BRepGProp 1e-9, {label:<15} "
                + ", ".join(f"{key} {value:.1e}" for key, value in errors.items())
                + "  (centroid, box: / box diagonal)"
            )


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    for mode, function in (("--child-scaling", child_scaling), ("--child-mesh", child_mesh_route)):
        if argv and argv[0] == mode:
            print(json.dumps(function(json.loads(argv[1]))))
            return 0
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--runs", type=int, default=7, help="runs per median (default 7)")
    parser.add_argument(
        "--quick", action="store_true", help="fewer scaling points, skip the cold CLI timing"
    )
    parser.add_argument(
        "--skip",
        nargs="*",
        default=[],
        choices=["scaling", "mesh", "cli", "workshop", "mass"],
        help="sections to skip",
    )
    parser.add_argument(
        "--mass-designs",
        type=int,
        default=20,
        help="random designs for the mass-properties accuracy check (default 20)",
    )
    parser.add_argument(
        "--out", type=Path, default=Path("bench_out/bench.json"), help="JSON report path"
    )
    args = parser.parse_args(argv)

    started = time.perf_counter()
    report: dict[str, Any] = {
        "machine": {
            "cores": os.cpu_count(),
            "python": platform.python_version(),
            "platform": platform.platform(),
            "load_average_at_start": os.getloadavg(),
        }
    }
    import cadquery

    report["machine"]["cadquery"] = cadquery.__version__
    print("stage times ...", flush=True)
    report["stage_times"] = stage_times(args.runs)
    if "workshop" not in args.skip:
        print(
            "workshop scenario (bore, flat, set screw, "
            "chamfer, 0.3 mm round edge, 0.5 mm fillet) ...",
            flush=True,
        )
        report["workshop"] = workshop_stage_times(max(1, min(args.runs, 3)))
        print(
            "  "
            + ", ".join(
                f"{key} {1000 * value:.0f} ms"
                for key, value in report["workshop"]["median_s"].items()
            )
        )
    if not args.quick and "cli" not in args.skip:
        print("cold CLI ...", flush=True)
        report["cli"] = cli_wall_time(3)
    if "mesh" not in args.skip:
        print("mesh-boolean route ...", flush=True)
        report["mesh_route"] = mesh_route(max(1, min(args.runs, 3)))
    if "scaling" not in args.skip:
        print("scaling ...", flush=True)
        report["scaling"] = scaling(args.quick)
    if "mass" not in args.skip:
        print("mass properties ...", flush=True)
        report["mass_properties"] = mass_properties_bench(args.runs, args.mass_designs)
    report["machine"]["load_average_at_end"] = os.getloadavg()
    report["seconds"] = time.perf_counter() - started
    print_report(report)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2, default=float) + "\n")
    print(f"\nbenchmark took {report['seconds']:.0f} s; JSON: {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
