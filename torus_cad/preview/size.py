"""The picture size of ``preview`` and ``build --preview``: ``WIDTHxHEIGHT`` in pixels, each side in
torus_cad.tolerances.PREVIEW_EDGE_RANGE. Apart from the renderer, so a bad size is refused before
the kernel loads."""

from __future__ import annotations

import re
from collections.abc import Sequence

from torus_cad.errors import ParameterError, shown
from torus_cad.tolerances import PREVIEW_EDGE_RANGE

#: Smallest and largest accepted picture edge, pixels.
MIN_EDGE, MAX_EDGE = PREVIEW_EDGE_RANGE


def parse_size(text: str, option: str = "--size") -> tuple[int, int]:
    """``"1200x600"`` -> ``(1200, 600)``; raise ParameterError (naming ``option``) for anything
    else."""
    # 9 digits: far over MAX_EDGE, an int
    match = re.fullmatch(r"\s*(\d{1,9})\s*[xX×]\s*(\d{1,9})\s*", text)
    if not match:
        raise ParameterError(
            f"{option} {shown(text)} must look like WIDTHxHEIGHT in pixels, e.g. 1200x600, each "
            f"side {MIN_EDGE}..{MAX_EDGE}"
        )
    return checked_size((int(match.group(1)), int(match.group(2))), f"{option} {text.strip()}")


def checked_size(size: Sequence[int], what: str = "preview size") -> tuple[int, int]:
    """``size`` (width, height) as ints; ParameterError naming ``what`` when a side is out of
    range."""
    width, height = (int(value) for value in size)
    for label, value in (("width", width), ("height", height)):
        if not MIN_EDGE <= value <= MAX_EDGE:
            raise ParameterError(
                f"{what}: {label} {value} px is out of range; allowed [{MIN_EDGE}, {MAX_EDGE}]"
            )
    return width, height
