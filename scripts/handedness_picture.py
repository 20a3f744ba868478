#!/usr/bin/env python3
"""Render the README's picture of a cw / ccw pair: the spec's blade and its mirror image, side by
side.

python scripts/handedness_picture.py             # docs/images/handedness_pair.png
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from PIL import Image

from torus_cad.preview.picture import write_preview
from torus_cad.propeller import build_propeller


def main(out: Path = Path("docs/images/handedness_pair.png")) -> int:
    pictures = []
    with tempfile.TemporaryDirectory() as folder:
        for handedness in ("cw", "ccw"):
            propeller = build_propeller(
                None, overrides={"handedness": handedness, "name": f"prop_{handedness}"}
            )
            spin = propeller.spin_to_push_air_down().value
            title = f'handedness = "{handedness}": turns {spin} seen from +z'
            path = write_preview(
                propeller, Path(folder) / f"{handedness}.png", (1000, 500), title=title
            )
            pictures.append(Image.open(path).convert("RGB"))
    pair = Image.new(
        "RGB", (pictures[0].width, sum(picture.height for picture in pictures)), "white"
    )
    for index, picture in enumerate(pictures):
        pair.paste(picture, (0, index * pictures[0].height))
    out.parent.mkdir(parents=True, exist_ok=True)
    pair.save(out)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
