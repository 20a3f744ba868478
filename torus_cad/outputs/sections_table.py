"""The blade-element table beside the STEP: ``<name>_sections.csv`` and ``<name>_sections.png``.

One row per section of the design (``resolution.sections``), columns as
:data:`CSV_COLUMNS` (mm and degrees; definitions in
:mod:`torus_cad.geometry.analysis.blade_elements`). The picture plots chord, beta and thickness
against r, so designers see what their quartics do; a loop blade passes each radius twice, so each
quantity is drawn as one line along the blade with the outgoing half solid and the returning half
dashed.
"""

from __future__ import annotations

import csv
import dataclasses
import io
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from torus_cad.design.described_geometry import propeller_geometry, sampled_blade_surface
from torus_cad.geometry.analysis.blade_elements import (
    NEARLY_RADIAL_FRACTION,
    BladeElements,
    blade_elements,
)
from torus_cad.geometry.blade.blade_surface import BladeSurface, sections_along
from torus_cad.geometry.blade.handedness import Handedness
from torus_cad.geometry.blade.trailing_edge import trailing_edge_thickness_mm
from torus_cad.geometry.blade.transforms import evaluate_quartic
from torus_cad.geometry.section.section import has_base
from torus_cad.runtime.files import atomic_path

#: CSV header: name in the file -> BladeElements attribute.
CSV_COLUMNS = {
    "s": "s",
    "r_mm": "radius_mm",
    "axial_mm": "axial_mm",
    "chord_mm": "chord_mm",
    "max_thickness_mm": "thickness_mm",
    "thickness_to_chord": "thickness_ratio",
    "beta_deg": "beta_deg",
    "geometric_pitch_mm": "pitch_mm",
    "position_angle_deg": "position_angle_deg",
    "radial_fraction": "radial_fraction",
    "trailing_edge_mm": "trailing_edge_mm",
}


def sections_csv_text(elements: BladeElements, trailing_edge_mm: np.ndarray | None = None) -> str:
    """The table as CSV text (header, then one row per section; 6 significant digits)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(CSV_COLUMNS)
    edge = (
        np.zeros(len(elements.s))
        if trailing_edge_mm is None
        else np.asarray(trailing_edge_mm, float)
    )
    for index in range(len(elements.s)):
        row = []
        for attribute in CSV_COLUMNS.values():
            value = (
                edge[index]
                if attribute == "trailing_edge_mm"
                else getattr(elements, attribute)[index]
            )
            row.append(f"{float(value):.6g}")
        writer.writerow(row)
    return buffer.getvalue()


#: beta is the angle of the chord *line*: the same line every 180 degrees.
BETA_PERIOD_DEG = 180.0


def plotted_beta_deg(elements: BladeElements) -> NDArray[np.float64]:
    """beta along s as the picture plots it: unwrapped with the 180-degree period of a line's angle,
    so the returning half of a toroidal blade (whose chord points back, e.g. -172 deg for +8 deg)
    continues the curve instead of jumping by about 175 degrees at the tip and dwarfing the rest.
    The table keeps the raw values."""
    return np.unwrap(np.asarray(elements.beta_deg, dtype=float), period=BETA_PERIOD_DEG)


def sections_png(
    elements: BladeElements, title: str = "", size_px: tuple[int, int] = (1500, 500)
) -> bytes:
    """Chord, beta and thickness against r, three panels side by side, as PNG bytes (matplotlib,
    off-screen)."""
    from matplotlib.figure import Figure  # no pyplot: no global state, no display

    dpi = 100
    figure = Figure(figsize=(size_px[0] / dpi, size_px[1] / dpi), dpi=dpi)
    figure.subplots_adjust(left=0.06, right=0.99, bottom=0.13, top=0.88, wspace=0.3)
    axes = figure.subplots(1, 3)
    tip = int(np.argmax(elements.radius_mm))
    halves = (
        (slice(0, tip + 1), "-", "outgoing (s up to the tip)"),
        (slice(tip, None), "--", "returning (s from the tip)"),
    )
    radial = elements.radial_fraction > NEARLY_RADIAL_FRACTION
    panels = (
        ("chord_mm", "chord (mm)"),
        ("beta_deg", "blade angle beta (deg, unwrapped mod 180)"),
        ("thickness_mm", "max thickness (mm)"),
    )
    for axis, (attribute, label) in zip(axes, panels):
        values = (
            plotted_beta_deg(elements) if attribute == "beta_deg" else getattr(elements, attribute)
        )
        for part, style, legend in halves:
            axis.plot(elements.radius_mm[part], values[part], style, color="tab:blue", label=legend)
        if attribute == "beta_deg" and np.any(radial):
            axis.plot(
                elements.radius_mm[radial],
                values[radial],
                "x",
                color="tab:red",
                label="chord nearly radial: beta says little",
            )
        axis.set_xlabel("r (mm)")
        axis.set_ylabel(label)
        axis.grid(True, alpha=0.3)
    axes[1].legend(fontsize="small")
    if title:
        figure.suptitle(title)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png")
    return buffer.getvalue()


def elements_of(surface: BladeSurface, spin: Handedness = Handedness.CW) -> BladeElements:
    """The blade-element table of a sampled blade surface."""
    frames = surface.frames
    return blade_elements(
        surface.s,
        surface.points,
        frames.origin,
        frames.normal,
        frames.binormal,
        surface.trailing_edge_index or 0,
        surface.lower_corner_index,
        spin,
    )


def trailing_edge_of(params: Any, s: NDArray[np.float64]) -> NDArray[np.float64]:
    """Thickness of the trailing edge (mm) of the sections at ``s`` (0 where sharp; a conventional
    blade's is sharp)."""
    if str(getattr(params, "kind", "toroidal")) == "conventional":
        return np.zeros(len(s))
    blade = propeller_geometry(params).blade
    laws = blade.laws
    sections = sections_along(blade, s)
    if not any(has_base(section) for section in sections):
        return np.zeros(len(s))
    return trailing_edge_thickness_mm(
        sections,
        evaluate_quartic(laws.angle_of_attack_deg, s),
        evaluate_quartic(laws.scale_x_mm, s),
        evaluate_quartic(laws.scale_y_mm, s),
    )


def sections_table_files(
    surface: BladeSurface, params: Any, spin: Handedness = Handedness.CW
) -> dict[str, tuple[str, bytes]]:
    """The blade-element table of the built blade ``surface``: ``{kind: (file name, content)}`` for
    ``<name>_sections.csv`` (``sections_csv``) and ``<name>_sections.png`` (``sections_png``).

    The table reads the surface the solid was lofted through (``resolution.points`` around each
    section): the thickness comes within 0.04 % of a 1000-point sampling at the default 80. A
    ``handedness = "ccw"`` part is that surface's mirror image through the XZ plane: the same
    table, with the position angles negated and the rotation counter-clockwise. Computed without
    touching the disk, so that it can run in a child process beside the build's other files.
    """
    elements = elements_of(surface, spin)
    # the part is the surface's mirror image (y -> -y)
    if str(getattr(params, "handedness", "cw")) == "ccw":
        elements = dataclasses.replace(
            elements, position_angle_deg=-elements.position_angle_deg, spin=elements.spin.opposite
        )
    csv_text = sections_csv_text(elements, trailing_edge_of(params, elements.s))
    return {
        "sections_csv": (f"{params.name}_sections.csv", csv_text.encode()),
        "sections_png": (
            f"{params.name}_sections.png",
            sections_png(elements, f"{params.name}: blade elements"),
        ),
    }


def design_sections_table_files(params: Any) -> dict[str, tuple[str, bytes]]:
    """:func:`sections_table_files` of the blade that the build of ``params`` lofts (its design
    targets resolved, its surface sampled, as torus_cad.propeller.build_propeller does), from the
    parameters
    alone: ``torus-cad build`` starts it in a child before the kernel loads, so that the picture is
    drawn on the second core while this process loads OpenCascade and builds."""
    from torus_cad.design.design_targets import resolve_design_targets

    resolved = resolve_design_targets(params).parameters
    return sections_table_files(sampled_blade_surface(resolved), resolved)


def write_files(files: dict[str, tuple[str, bytes]], out_dir: Path) -> dict[str, Path]:
    """Write :func:`sections_table_files` into ``out_dir``, each atomically; their paths by kind."""
    paths = {}
    for kind, (name, content) in files.items():
        with atomic_path(out_dir / name) as temp:
            temp.write_bytes(content)
        paths[kind] = out_dir / name
    return paths


def write_sections_table(
    surface: BladeSurface, params: Any, out_dir: Path, spin: Handedness = Handedness.CW
) -> dict[str, Path]:
    """Write ``<name>_sections.csv`` and ``<name>_sections.png`` into ``out_dir``; their paths by
    kind."""
    return write_files(sections_table_files(surface, params, spin), out_dir)
