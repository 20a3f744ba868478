"""Render the example designs into one picture: docs/images/gallery.png (run from the repo root).

Builds every design in examples/ (not the sweep files), renders each with torus_cad.preview.picture
(isometric and axial views), writes its name, blade count, tip diameter and the geometric
pitch at 75 % of the tip radius under it, and tiles the pictures two to a row.

    python scripts/gallery.py [--out docs/images/gallery.png] [--tile 900x450] [designs.toml ...]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from torus_cad.design.described_geometry import sampled_blade_surface
from torus_cad.design.design_targets import tip_radius_mm
from torus_cad.geometry.analysis.blade_elements import NEARLY_RADIAL_FRACTION
from torus_cad.outputs.sections_table import elements_of
from torus_cad.preview.picture import render_preview, write_png
from torus_cad.preview.size import parse_size
from torus_cad.propeller import build_propeller

EXAMPLES = Path("examples")

#: Files in examples/ that are not in the gallery: sweep definitions, and the workshop examples
#: (mounting, fillet and handedness options; docs/images/handedness_pair.png shows those).
NOT_IN_GALLERY = ("sweep_*.toml", "workshop_*.toml")


def gallery_designs(folder: Path = EXAMPLES) -> list[Path]:
    """The gallery's design files, in name order."""
    return sorted(
        path
        for path in folder.glob("*.toml")
        if not any(path.match(skip) for skip in NOT_IN_GALLERY)
    )


def caption(propeller) -> str:
    """Name, blades, tip diameter and pitch at 75 % radius (mm), as the designer reads them."""
    params = propeller.parameters
    diameter = 2.0 * tip_radius_mm(params)
    elements = elements_of(sampled_blade_surface(params, sections=201))
    radius = 0.375 * diameter
    pitch = elements.pitch_at_radius(radius)
    radial = np.interp(
        radius,
        np.sort(elements.radius_mm),
        elements.radial_fraction[np.argsort(elements.radius_mm)],
    )
    if not len(pitch) or radial > NEARLY_RADIAL_FRACTION:
        pitch_text = "- (chords nearly radial there)"
    else:
        pitch_text = " / ".join(f"{value:.0f}" for value in pitch) + " mm"
    return (
        f"{params.name}: {params.blades} blades, D {diameter:.0f} mm, pitch at 0.75 R {pitch_text}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "designs", nargs="*", type=Path, help="design files (default: examples/*.toml)"
    )
    parser.add_argument("--out", type=Path, default=Path("docs/images/gallery.png"))
    parser.add_argument(
        "--tile", default="1000x420", help="size of each design's picture, WxH pixels"
    )
    args = parser.parse_args(argv)
    width, height = parse_size(args.tile, "--tile")
    tiles = []
    for path in args.designs or gallery_designs():
        start = time.perf_counter()
        propeller = build_propeller(path)
        tiles.append(render_preview(propeller, (width, height), title=caption(propeller)))
        print(f"{path}: {time.perf_counter() - start:.1f} s", file=sys.stderr)
    columns = 2
    rows = -(-len(tiles) // columns)
    sheet = np.full((rows * height, columns * width, tiles[0].shape[2]), 255, dtype=np.uint8)
    for index, tile in enumerate(tiles):
        row, column = divmod(index, columns)
        sheet[row * height : (row + 1) * height, column * width : (column + 1) * width] = tile
    args.out.parent.mkdir(parents=True, exist_ok=True)
    write_png(sheet, args.out)
    print(f"wrote {args.out} ({sheet.shape[1]}x{sheet.shape[0]} px, {len(tiles)} designs)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
