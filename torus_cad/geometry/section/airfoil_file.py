"""Airfoils from coordinate files (.dat, the UIUC database's two layouts) as smooth sections.

Layouts (https://m-selig.ae.illinois.edu/ads/coord_database.html):

* **Selig**: a name line, then x y pairs in one loop from the trailing edge over the upper
  surface to the leading edge and back along the lower surface to the trailing edge.
* **Lednicer**: a name line, a line with the two point counts (e.g. ``17. 17.``), then the
  upper surface from the leading edge to the trailing edge, then the lower surface likewise
  (blocks usually separated by blank lines).

Both become one point loop in Selig order. A cubic spline (scipy ``CubicSpline``, not-a-knot
ends, no periodicity) is laid through the loop against its cumulative chord length, so the
curve is C2 everywhere, across the leading edge too. A file already in chord units (a point
at the origin, the trailing edge's mid point at (1, 0)) keeps its leading edge, as the
database's files and NACA tables place it; otherwise the leading edge is the point of the
curve farthest from the trailing edge's mid point (XFOIL's definition), and the section is
moved, turned and scaled so that the leading edge is at (0, 0) and the trailing edge's mid
point at (1, 0). Each half runs from the leading edge (u = 0) to its trailing-edge end
(u = 1) linearly in the spline's parameter, so |df/du| is bounded and nearly constant, and
the spec's §5 resampling applies unchanged. The same points in either layout give the same
loop, hence the same section.

Accuracy: a file written from the NACA formulas with 81 cosine-spaced stations per surface (161
points in the loop, the density of the database's files) comes back within 1.5e-6 chord of the
analytic section for the NACA 2412 and 0012 family, 3.0e-6 for the 4412 (41 stations: 1.1e-5);
the camber line's curvature jump at p keeps cambered sections from converging faster
(``tests/test_airfoil_file.py`` checks :data:`INTERPOLATION_ERROR_LIMIT` at 81 stations).

Blunt trailing edge: :meth:`AirfoilFile.with_trailing_edge_gap` moves the upper half up and the
lower half down by (Delta / 2) u^8 (the NACA law's (g / 2) t^4 with t = u^2), so that the two
trailing-edge ends are ``gap`` apart in y; a file whose trailing edge is open already keeps
its gap when no thickness is asked for. :meth:`AirfoilFile.sharpened` closes an open edge the
same way in x and y, so that both ends meet (the spec's sharp trailing edge).

A coordinate file is untrusted input, read by torus_cad.runtime.input_files like a configuration
file: a regular file only (no device, named pipe, socket or folder), at most
:data:`~torus_cad.tolerances.AIRFOIL_FILE_MAX_BYTES`, at most
:data:`~torus_cad.tolerances.AIRFOIL_FILE_MAX_POINTS` points, and the parsing and the crossing
checks within :data:`~torus_cad.geometry.section.airfoil_file.AIRFOIL_FILE_TIME_LIMIT_S`. Malformed
files raise ParameterError naming the file, the line and what was expected there, never quoting the
line (the path may name any file the user can read): no coordinates, a line that is not two numbers,
a coordinate that is not finite or beyond
:data:`~torus_cad.geometry.section.airfoil_file.AIRFOIL_COORDINATE_LIMIT`, one surface only,
surfaces that cross, a chord of zero. The crossing test compares only segments whose bounding boxes
overlap (a sort and sweep over x), O(n log n) for a section, not all O(n^2) pairs.
"""

from __future__ import annotations

import copy
import math
from functools import lru_cache
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize_scalar

from torus_cad.errors import BudgetError, ParameterError
from torus_cad.runtime.input_files import TimeBudget, decode_text, read_untrusted_bytes
from torus_cad.tolerances import AIRFOIL_FILE_MAX_BYTES, AIRFOIL_FILE_MAX_POINTS

#: Largest magnitude of a coordinate in an airfoil file (any length unit: the section is scaled to
#: chord units); larger values overflow the chord and area computations.
AIRFOIL_COORDINATE_LIMIT = 1e6

#: Seconds the parsing and checks of one airfoil coordinate file may take before it is refused.
AIRFOIL_FILE_TIME_LIMIT_S = 10.0


#: Largest distance (chord units) between a file's spline and the analytic NACA section it was
#: written from, at 81 cosine-spaced stations per surface (measured: at most 3.0e-6; module
#: docstring).
INTERPOLATION_ERROR_LIMIT = 1e-5

#: A file with a point within this of the origin and its trailing edge's mid point within this of
#: (1, 0) is taken to be in chord units already (its leading edge is kept).
NORMALISED_TOLERANCE = 1e-5

#: Fewest points a surface needs for a cubic spline with a meaningful leading edge.
MINIMUM_POINTS_PER_SURFACE = 4

#: Files larger than this are refused (a coordinate file is a few kB).
MAXIMUM_FILE_BYTES = AIRFOIL_FILE_MAX_BYTES

#: Points closer than this (times the largest coordinate, at least 1) are one point: a repeated
#: point of a file, and the trailing-edge ends of a closed section, which the spline's two ends
#: reproduce only to round-off (~1e-19 chord).
COINCIDENT_RELATIVE = 1e-12

#: What the file is called in messages.
_WHAT = "airfoil file"

#: Most segment pairs per segment the crossing test may examine (a section has about 3: each segment
#: overlaps its neighbours and the facing surface's segments in x).
_CANDIDATES_PER_SEGMENT = 64


class AirfoilFile:
    """A section read from a coordinate file (implements
    :class:`~torus_cad.geometry.section.section.Section`).

    Attributes:
        name: the file's first line (or its file name when the file has no name line).
        source: the path it was read from (for messages).
        loop: ``(n, 2)`` the file's points in Selig order, in chord units (leading edge at the
            origin).
        lines: ``(n,)`` the file line of each point of ``loop``.
        trailing_edge_extra: added trailing-edge thickness Delta (chord units, see the module
            docstring).
        trailing_edge_shift_x: the same law's offset in x (chord units; nonzero only once
            sharpened).
    """

    def __init__(
        self, name: str, source: str, loop: NDArray[np.float64], lines: NDArray[np.int64]
    ) -> None:
        self.name = name
        self.source = source
        self.lines = lines
        steps = np.linalg.norm(np.diff(loop, axis=0), axis=1)
        sigma = np.concatenate([[0.0], np.cumsum(steps)])
        raw = CubicSpline(sigma, loop, bc_type="not-a-knot")
        trailing_middle = 0.5 * (loop[0] + loop[-1])
        sigma_le = _leading_edge_parameter(raw, sigma, loop, trailing_middle)
        leading = raw(sigma_le)
        chord_vector = trailing_middle - leading
        chord = float(np.linalg.norm(chord_vector))
        if not chord > 1e-9 * max(1.0, float(np.abs(loop).max())):
            raise ParameterError(
                f"{_WHAT} {source!r} line {int(lines[0])}: the chord is zero "
                "(leading and trailing edge coincide)"
            )
        cos, sin = chord_vector / chord
        # Rows map a file point p to chord units: A (p - leading), A = rotation to +x / chord.
        self._matrix = np.array([[cos, sin], [-sin, cos]]) / chord
        self._leading = leading
        self._spline = raw
        self._sigma_le = float(sigma_le)
        self._sigma_end = float(sigma[-1])
        self.trailing_edge_extra = 0.0
        self.trailing_edge_shift_x = 0.0
        self.loop = self._to_chord_units(loop)

    # -- the Section protocol ----------------------------------------------------------------
    @property
    def kinks(self) -> tuple[float, ...]:
        """None: the spline is C2 everywhere."""
        return ()

    def _sigma(self, u: NDArray[np.float64], upper: bool) -> tuple[NDArray[np.float64], float]:
        if upper:
            return self._sigma_le * (1.0 - u), -self._sigma_le
        return self._sigma_le + u * (
            self._sigma_end - self._sigma_le
        ), self._sigma_end - self._sigma_le

    def _to_chord_units(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        return (points - self._leading) @ self._matrix.T

    def points_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """Points of the upper or lower half at u in [0, 1] (0 = leading edge): ``(len(u), 2)``."""
        u = np.atleast_1d(np.asarray(root_chord, dtype=float))
        sigma, _ = self._sigma(u, upper)
        points = self._to_chord_units(self._spline(sigma))
        half = 0.5 if upper else -0.5
        points += (
            half
            * np.array([self.trailing_edge_shift_x, self.trailing_edge_extra])
            * (u**8)[:, None]
        )
        return points

    def speed_on_half(self, root_chord: ArrayLike, upper: bool) -> NDArray[np.float64]:
        """|d f / du| on the upper or lower half, shape of ``u``."""
        u = np.atleast_1d(np.asarray(root_chord, dtype=float))
        sigma, rate = self._sigma(u, upper)
        velocity = self._spline(sigma, 1) @ self._matrix.T * rate
        velocity += (
            (4.0 if upper else -4.0)
            * np.array([self.trailing_edge_shift_x, self.trailing_edge_extra])
            * (u**7)[:, None]
        )
        return np.linalg.norm(velocity, axis=-1)

    def with_trailing_edge_gap(self, gap: float) -> AirfoilFile:
        """A copy whose trailing-edge ends are ``gap`` apart in y (chord units; the x offset is the
        file's)."""
        result = copy.copy(self)
        result.trailing_edge_extra = 0.0
        ends = [result.points_on_half(np.array([1.0]), side)[0] for side in (True, False)]
        result.trailing_edge_extra = float(gap) - float(ends[0][1] - ends[1][1])
        return result

    def sharpened(self) -> AirfoilFile:
        """A copy whose trailing-edge ends meet (module docstring): a sharp section."""
        result = copy.copy(self)
        result.trailing_edge_extra = result.trailing_edge_shift_x = 0.0
        upper, lower = (result.points_on_half(np.array([1.0]), side)[0] for side in (True, False))
        result.trailing_edge_shift_x, result.trailing_edge_extra = (lower - upper).tolist()
        return result

    def __repr__(self) -> str:
        return f"AirfoilFile({self.name!r}, source={self.source!r}, points={len(self.loop)})"


def _leading_edge_parameter(
    spline: CubicSpline,
    sigma: NDArray[np.float64],
    loop: NDArray[np.float64],
    trailing_middle: NDArray[np.float64],
) -> float:
    """The spline parameter of the leading edge.

    A file already in chord units (a point at the origin, the trailing edge's mid point at
    (1, 0), both within :data:`NORMALISED_TOLERANCE`) keeps its author's leading edge, the
    point at the origin: for cambered NACA sections that is the camber line's start, which is
    not the point farthest from the trailing edge. Otherwise the leading edge is the curve's
    point farthest from the trailing edge's mid point (XFOIL's definition).
    """
    at_origin = np.linalg.norm(loop, axis=1)
    index = int(np.argmin(at_origin))
    if (
        at_origin[index] < NORMALISED_TOLERANCE
        and np.linalg.norm(trailing_middle - (1.0, 0.0)) < NORMALISED_TOLERANCE
    ):
        return float(sigma[index])
    index = int(np.argmax(np.linalg.norm(loop - trailing_middle, axis=1)))
    low, high = sigma[max(index - 1, 0)], sigma[min(index + 1, len(sigma) - 1)]
    found = minimize_scalar(
        lambda value: -float(np.linalg.norm(spline(value) - trailing_middle)),
        bounds=(low, high),
        method="bounded",
        options={"xatol": 1e-13},
    )
    return float(found.x)


# -- reading -------------------------------------------------------------------------------------


def load_airfoil_file(path: str | Path) -> AirfoilFile:
    """:func:`read_airfoil_file`, read once per file version (path, size, modification time)."""
    path = Path(path)
    try:
        # never blocks, not even on a named pipe; the reader checks the file it opens
        status = path.stat()
    except OSError as error:
        raise ParameterError(f"cannot read {_WHAT} {str(path)!r}: {error.strerror}") from None
    return _load_cached(str(path.resolve()), status.st_size, status.st_mtime_ns, str(path))


@lru_cache(maxsize=32)
def _load_cached(resolved: str, size: int, modified_ns: int, path: str) -> AirfoilFile:
    """The file read by its path as given (messages name it so, not a symlink's target)."""
    return read_airfoil_file(path)


def read_airfoil_file(path: str | Path) -> AirfoilFile:
    """Read a Selig or Lednicer coordinate file; ParameterError naming the file and line if
    malformed.

    The file is untrusted: see the module docstring for what is refused and the limits.
    """
    raw = read_untrusted_bytes(path, _WHAT, AIRFOIL_FILE_MAX_BYTES)
    try:
        # empty: "no coordinates", naming line 1
        text = decode_text(raw, str(path), _WHAT, empty_ok=True)
    except ParameterError:
        if b"\x00" in raw:
            raise
        text = raw.decode("latin-1")  # older database files carry Latin-1 names
    return parse_airfoil_text(text, str(path))


def parse_airfoil_text(text: str, source: str = "<text>") -> AirfoilFile:
    """Parse the text of a Selig or Lednicer coordinate file (``source`` names it in messages)."""
    budget = TimeBudget(source, _WHAT, AIRFOIL_FILE_TIME_LIMIT_S)
    name, rows = _numeric_rows(text, source, budget)
    if not rows:
        raise ParameterError(
            f"{_WHAT} {source!r} line 1: no coordinates found (expected lines of 'x y')"
        )
    _, (first_x, first_y) = rows[0]
    coordinates = np.array([values for _, values in rows], dtype=float)
    if np.linalg.norm(np.ptp(coordinates, axis=0)) <= 1e-12 * max(
        1.0, float(np.abs(coordinates).max())
    ):
        raise ParameterError(
            f"{_WHAT} {source!r} line {rows[0][0]}: the chord is zero (every point is the same)"
        )
    if first_x >= 2.0 and first_y >= 2.0 and first_x.is_integer() and first_y.is_integer():
        loop, lines = _lednicer_loop(rows, source)
    else:
        loop, lines = _selig_loop(rows, source)
    loop, lines = _without_repeats(loop, lines)
    if _signed_area(loop) < 0.0:  # stored lower surface first: turn it into Selig's order
        loop, lines = loop[::-1].copy(), lines[::-1].copy()
    _check_no_crossing(loop, lines, source, budget)
    section = AirfoilFile(name or Path(source).stem, source, loop, lines)
    budget.check("fitting the spline")
    _check_smooth_section(section, source, budget)
    return section


def _numeric_rows(
    text: str, source: str, budget: TimeBudget
) -> tuple[str, list[tuple[int, tuple[float, float]]]]:
    """The name line and every ``(line number, (x, y))`` row; other lines after the data are errors.

    Refused (naming the line, never quoting it): a line that is not two numbers after the first
    coordinates, a coordinate that is not finite or over :data:`AIRFOIL_COORDINATE_LIMIT`, and
    more than :data:`AIRFOIL_FILE_MAX_POINTS` points (BudgetError, as soon as the count passes it).
    """
    name = ""
    rows: list[tuple[int, tuple[float, float]]] = []
    for number, line in enumerate(text.splitlines(), start=1):
        content = line.split("#", 1)[0].strip()
        if not content:
            continue
        values = _two_numbers(content)
        if values is None:
            if not rows and not name:
                name = content
                continue
            raise ParameterError(
                f"{_WHAT} {source!r} line {number}: expected two numbers 'x y' (only the first "
                "line before the coordinates may be a name)"
            )
        if not all(math.isfinite(value) for value in values):
            raise ParameterError(
                f"{_WHAT} {source!r} line {number}: coordinates must be finite numbers"
            )
        if max(abs(values[0]), abs(values[1])) > AIRFOIL_COORDINATE_LIMIT:
            raise ParameterError(
                f"{_WHAT} {source!r} line {number}: a coordinate is out of range; allowed "
                f"[-{AIRFOIL_COORDINATE_LIMIT:g}, {AIRFOIL_COORDINATE_LIMIT:g}]"
            )
        rows.append((number, values))
        if len(rows) > AIRFOIL_FILE_MAX_POINTS:
            raise BudgetError(
                f"{_WHAT} {source!r} line {number}: more than "
                f"{AIRFOIL_FILE_MAX_POINTS:,} points, the "
                f"limit for a coordinate file (the checks of a section grow with its points)"
            )
        if not len(rows) % 4096:
            budget.check("reading the coordinates")
    budget.check("reading the coordinates")
    return name, rows


def _two_numbers(content: str) -> tuple[float, float] | None:
    parts = content.replace(",", " ").split()
    if len(parts) != 2:
        return None
    try:
        return float(parts[0]), float(parts[1])
    except ValueError:
        return None


def _lednicer_loop(
    rows: list[tuple[int, tuple[float, float]]], source: str
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    header_line, (upper_count, lower_count) = rows[0]
    upper_count, lower_count = int(upper_count), int(lower_count)
    data = rows[1:]
    if len(data) < upper_count + lower_count:
        have = max(len(data) - upper_count, 0)
        where = data[-1][0] if data else header_line
        raise ParameterError(
            f"airfoil file {source!r} line {where}: Lednicer "
            f"layout promises {upper_count} upper and {lower_count} "
            f"lower points (line {header_line}) but the file "
            f"ends after {min(len(data), upper_count)} upper and "
            f"{have} lower points" + ("; only one surface is given" if have == 0 else "")
        )
    if len(data) > upper_count + lower_count:
        raise ParameterError(
            f"{_WHAT} {source!r} line {data[upper_count + lower_count][0]}: more points than "
            f"the {upper_count} + {lower_count} promised on line {header_line}"
        )
    for count, label in ((upper_count, "upper"), (lower_count, "lower")):
        if count < MINIMUM_POINTS_PER_SURFACE:
            raise ParameterError(
                f"{_WHAT} {source!r} line {header_line}: the {label} surface has {count} points; "
                f"at least {MINIMUM_POINTS_PER_SURFACE} are needed"
            )
    upper, lower = data[:upper_count], data[upper_count:]
    # trailing edge -> upper -> leading edge -> lower -> trailing edge
    ordered = upper[::-1] + lower
    return (
        np.array([values for _, values in ordered], dtype=float),
        np.array([number for number, _ in ordered], dtype=np.int64),
    )


def _selig_loop(
    rows: list[tuple[int, tuple[float, float]]], source: str
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    loop = np.array([values for _, values in rows], dtype=float)
    lines = np.array([number for number, _ in rows], dtype=np.int64)
    if len(loop) < 2 * MINIMUM_POINTS_PER_SURFACE - 1:
        raise ParameterError(
            f"{_WHAT} {source!r} line {lines[-1]}: {len(loop)} points are too few for two "
            f"surfaces (at least {2 * MINIMUM_POINTS_PER_SURFACE - 1})"
        )
    trailing_middle = 0.5 * (loop[0] + loop[-1])
    leading = int(np.argmax(np.linalg.norm(loop - trailing_middle, axis=1)))
    extent = float(np.linalg.norm(loop.max(axis=0) - loop.min(axis=0)))
    # a loop starts and ends at the trailing edge
    ends_apart = np.linalg.norm(loop[0] - loop[-1]) > 0.5 * extent
    if (
        ends_apart
        or leading < MINIMUM_POINTS_PER_SURFACE - 1
        or leading > len(loop) - MINIMUM_POINTS_PER_SURFACE
    ):
        raise ParameterError(
            f"airfoil file {source!r} line {lines[-1]}: only one "
            "surface is given (the coordinates end here; a Selig "
            "loop runs from the trailing edge over one surface "
            "to the leading edge and back over the other, "
            f"at least {MINIMUM_POINTS_PER_SURFACE} points on each)"
        )
    return loop, lines


def _without_repeats(
    loop: NDArray[np.float64], lines: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Drop points equal to their predecessor (Lednicer's doubled leading edge)."""
    keep = np.concatenate(
        [
            [True],
            np.linalg.norm(np.diff(loop, axis=0), axis=1)
            > COINCIDENT_RELATIVE * max(1.0, np.abs(loop).max()),
        ]
    )
    return loop[keep], lines[keep]


def _signed_area(loop: NDArray[np.float64]) -> float:
    x, y = loop[:, 0], loop[:, 1]
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def _segments(
    polygon: NDArray[np.float64], closed: bool
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Start and end points ``(m, 2)`` of the polygon's segments (m = n closed, n - 1 open)."""
    if closed:
        return polygon, np.roll(polygon, -1, axis=0)
    return polygon[:-1], polygon[1:]


def _candidate_pairs(
    start: NDArray[np.float64], end: NDArray[np.float64], limit: int
) -> NDArray[np.int64]:
    """Pairs ``(k, 2)`` (i < j) of segments whose bounding boxes overlap: every crossing pair is
    among them.

    Sort and sweep: with the segments sorted by their smallest x, the ones whose x-range overlaps
    segment i's and that start after it are a contiguous run found by binary search, so the pairs
    are counted in O(n log n) before any is made, and made in O(k) for k overlapping x-ranges. A
    section's two surfaces overlap only where they face each other (k ~ 3n). BudgetError if k
    exceeds ``limit`` (segments stacked far more steeply than any airfoil's).
    """
    low_x, high_x = np.minimum(start[:, 0], end[:, 0]), np.maximum(start[:, 0], end[:, 0])
    order = np.argsort(low_x, kind="stable")
    sorted_low = low_x[order]
    run = np.searchsorted(sorted_low, high_x[order], side="right") - np.arange(len(order)) - 1
    run = np.maximum(run, 0)
    total = int(run.sum())
    if total > limit:
        raise BudgetError(
            f"the surfaces cannot be checked for crossings within the budget: {total:,} segment "
            f"pairs overlap in x, over the limit of {limit:,}"
        )
    first = np.repeat(np.arange(len(order)), run)
    offset = np.arange(total) - np.repeat(np.cumsum(run) - run, run)
    pairs = np.sort(np.stack([order[first], order[first + 1 + offset]], axis=1), axis=1)
    low_y, high_y = np.minimum(start[:, 1], end[:, 1]), np.maximum(start[:, 1], end[:, 1])
    overlap_y = (low_y[pairs[:, 0]] <= high_y[pairs[:, 1]]) & (
        low_y[pairs[:, 1]] <= high_y[pairs[:, 0]]
    )
    return pairs[overlap_y]


def first_crossing(polygon: NDArray[np.float64], closed: bool) -> tuple[int, int] | None:
    """Indices (i, j), i < j, of the first pair of non-adjacent segments that properly cross, or
    None.

    Only the candidate pairs of :func:`_candidate_pairs` are tested exactly. A closed polygon whose
    last point is its first (within :data:`COINCIDENT_RELATIVE`) closes on that point: its ends,
    equal but for round-off, would otherwise make a bow-tie of size ~1e-19 whose two sides "cross"
    (a closed ellipse was refused so). Indices refer to ``polygon`` as given.
    """
    if (
        closed
        and len(polygon) > 3
        and (
            np.linalg.norm(polygon[-1] - polygon[0])
            <= COINCIDENT_RELATIVE * max(1.0, float(np.abs(polygon).max()))
        )
    ):
        polygon = polygon[:-1]
    start, end = _segments(polygon, closed)
    count = len(start)
    if count < 2:
        return None
    pairs = _candidate_pairs(start, end, _CANDIDATES_PER_SEGMENT * count)
    gap = pairs[:, 1] - pairs[:, 0]
    pairs = pairs[(gap > 1) & ~(closed & (gap == count - 1))]

    def orientation(
        a: NDArray[np.float64], b: NDArray[np.float64], c: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        return np.sign(
            (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        )

    p, q, r, s = start[pairs[:, 0]], end[pairs[:, 0]], start[pairs[:, 1]], end[pairs[:, 1]]
    crossing = (orientation(p, q, r) * orientation(p, q, s) < 0) & (
        orientation(r, s, p) * orientation(r, s, q) < 0
    )
    found = pairs[crossing]
    if not len(found):
        return None
    i, j = found[np.lexsort((found[:, 1], found[:, 0]))[0]]
    return int(i), int(j)


def _check_no_crossing(
    loop: NDArray[np.float64], lines: NDArray[np.int64], source: str, budget: TimeBudget
) -> None:
    try:
        crossing = first_crossing(loop, closed=True)
    except BudgetError as error:
        raise BudgetError(f"{_WHAT} {source!r}: {error}") from None
    budget.check("checking the surfaces for crossings")
    if crossing is not None:
        i, j = crossing
        raise ParameterError(
            f"{_WHAT} {source!r} line {lines[i]}: the surfaces cross (the segment from line "
            f"{lines[i]} crosses the one from line {lines[j]})"
        )


def _check_smooth_section(
    section: AirfoilFile, source: str, budget: TimeBudget, samples: int = 400
) -> None:
    """The spline through the points must not cross itself either (an overshoot between sparse
    points)."""
    u = np.linspace(0.0, 1.0, samples)
    upper, lower = section.points_on_half(u, True), section.points_on_half(u, False)
    # trailing edge -> upper -> leading edge -> lower
    polygon = np.concatenate([upper[::-1], lower[1:]])
    crossing = first_crossing(polygon, closed=True)
    budget.check("checking the smooth curve for crossings")
    if crossing is not None:
        point = polygon[crossing[0]]
        nearest = int(np.argmin(np.linalg.norm(section.loop - point, axis=1)))
        raise ParameterError(
            f"{_WHAT} {source!r} line {section.lines[nearest]}: the surfaces cross (the smooth "
            "curve through the points runs into itself near this point; check the coordinates)"
        )
    if upper[-1, 1] < lower[-1, 1] - 1e-12:
        raise ParameterError(
            f"{_WHAT} {source!r} line {section.lines[0]}: the surfaces cross at the trailing "
            "edge (the upper surface ends below the lower one)"
        )


def write_selig_file(path: str | Path, name: str, loop: ArrayLike, digits: int = 7) -> Path:
    """Write a Selig-layout file: the name line, then one 'x y' line per point of ``loop`` ``(n,
    2)``."""
    path = Path(path)
    lines = [name] + [f"{x: .{digits}f} {y: .{digits}f}" for x, y in np.asarray(loop, dtype=float)]
    path.write_text("\n".join(lines) + "\n")
    return path


def write_lednicer_file(
    path: str | Path, name: str, upper: ArrayLike, lower: ArrayLike, digits: int = 7
) -> Path:
    """Write a Lednicer-layout file: upper and lower ``(k, 2)`` both from the leading edge to the
    trailing edge."""
    path = Path(path)
    upper, lower = np.asarray(upper, dtype=float), np.asarray(lower, dtype=float)
    lines = [name, f"{len(upper)}. {len(lower)}.", ""]
    lines += [f"{x: .{digits}f} {y: .{digits}f}" for x, y in upper] + [""]
    lines += [f"{x: .{digits}f} {y: .{digits}f}" for x, y in lower]
    path.write_text("\n".join(lines) + "\n")
    return path
