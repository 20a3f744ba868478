"""Random in-range designs for fuzzing: a point of the unit cube becomes a design.

Used by ``scripts/fuzz.py`` (N random designs run on the batch runner, tallied, failures
saved for replay) and by the hypothesis properties in ``tests/test_robustness.py``; both draw
designs through the same function, :func:`design_dict_from_unit`. Every design it returns
passes the per-field checks, so the only acceptable outcomes of building it are a valid
closed solid or a clear refusal (:attr:`torus_cad.batch.Outcome.acceptable`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from typing import Any

import numpy as np

from torus_cad.batch.job import DesignTask
from torus_cad.geometry.blade.transforms import quartic_minimum
from torus_cad.parameters import ParameterSpec, PropellerParameters, parameter_specs

#: Length of the unit vector that :func:`design_from_unit` consumes.
UNIT_DIMENSION = 39

_SPECS: dict[str, ParameterSpec] = {spec.key: spec for spec in parameter_specs()}


def fuzz_range(key: str) -> tuple[float, float]:
    """The interval the sampler draws parameter ``key`` from: the schema's ``fuzz`` range of the
    field (its allowed range unless the declaration narrows it with ``param(..., fuzz=(low,
    high))``)."""
    bounds = _SPECS[key].fuzz
    if bounds is None or bounds.low is None or bounds.high is None:
        raise ValueError(
            f"{key} has no finite fuzz range; declare one with param(..., fuzz=(low, high))"
        )
    return float(bounds.low), float(bounds.high)


def _default(key: str) -> Any:
    return _SPECS[key].default


def _choice(u: float, key: str) -> str:
    """One of the choice parameter's values, each with the same chance."""
    choices = _SPECS[key].choices
    return str(choices[min(len(choices) - 1, int(u * len(choices)))].value)


def _whole(u: float, key: str) -> int:
    """A whole number in the field's fuzz range, each with the same chance."""
    low, high = (int(bound) for bound in fuzz_range(key))
    return low + min(high - low, int(u * (high - low + 1)))


# -- sampling --------------------------------------------------------------------------------


def _lerp(u: float, low: float, high: float) -> float:
    return low + (high - low) * float(u)


def _log_lerp(u: float, low: float, high: float) -> float:
    return math.exp(_lerp(u, math.log(low), math.log(high)))


def _positive_quartic(
    ends: tuple[float, float], bulge: float, wiggle: float, floor: float
) -> tuple[float, ...]:
    """A scale quartic (mm) that stays positive on [0, 1].

    S(s) = v0 (1 - s) + v1 s + 4 h s (1 - s) + 16 w s^2 (1 - s)^2 with end values ``ends``,
    mid-span ``bulge`` h and ``wiggle`` w; e is raised if needed so the minimum is ``floor`` > 0.
    """
    v0, v1 = ends
    h, w = bulge, wiggle
    coefficients = [16 * w, -32 * w, 16 * w - 4 * h, v1 - v0 + 4 * h, v0]  # highest power first
    low, _ = quartic_minimum(tuple(coefficients))
    if low < floor:
        coefficients[4] += floor - low
    while quartic_minimum(tuple(coefficients))[0] <= 0.0:  # guard against rounding
        coefficients[4] += floor
    return tuple(float(value) for value in coefficients)


def design_dict_from_unit(
    u: Sequence[float],
    name: str = "fuzz",
    sections: tuple[int, int] | None = None,
    points: tuple[int, int] | None = None,
) -> dict[str, Any]:
    """Map ``u`` in [0, 1]^UNIT_DIMENSION to a design as a nested dict (the TOML layout).

    The first number sets a *wildness* w in [0, 1]: every geometric quantity is the default
    design's (scaled to the sampled hub) perturbed by up to w times its own range, so a run
    covers near-default propellers (mostly valid) through wild ones (mostly refused).

    Every field drawn directly stays in its fuzz range from the schema (:func:`fuzz_range`:
    blades, hub radius and length, phase, camber, camber position, thickness, pivot, frame
    kind, resolution, STL deflections, STEP schema), and starts from its declared default.
    The centerline's control points and the quartics follow the blade's shape instead: span
    0.3-1.15 of the blade pitch, control-point heights 0.1-6.6 R and y_L from far above to
    below the hub; angle of attack +-90 degrees plus quartic terms up to +-250 degrees; chord
    and thickness scales whose ends, bulge and wiggle vary by factors of 3 (kept positive).
    Rules that tie fields together (an airfoil too thick for its camber, ...) may still refuse
    the design with ParameterError, which counts as a clear refusal. ``sections`` and
    ``points`` narrow the sampling resolution further, inclusive (default: their fuzz ranges).
    """
    u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
    if u.shape != (UNIT_DIMENSION,):
        raise ValueError(
            f"design_dict_from_unit needs {UNIT_DIMENSION} numbers in [0, 1], got shape {u.shape}"
        )
    it: Iterator[float] = iter(u.tolist())

    def take() -> float:
        return next(it)

    wild = take()

    def vary(value: float, factor: float) -> float:
        """``value`` times a factor in [1/factor, factor]^wild (log-uniform)."""
        return value * math.exp(wild * _lerp(take(), -1.0, 1.0) * math.log(factor))

    def shift(value: float, spread: float) -> float:
        """``value`` plus up to +-wild * spread (offsets below 1e-9 of the spread snap to 0)."""
        offset = wild * _lerp(take(), -1.0, 1.0) * spread
        # Subnormal coefficients (hypothesis finds them) break np.roots in quartic_minimum; that bug
        # has its own regression test in tests/test_malformed_config.py; here they would only mask
        # the geometry this sampler is for.
        return value + (offset if abs(offset) > 1e-9 * spread else 0.0)

    blades = _whole(take(), "blades")
    radius = float(np.clip(vary(_default("hub.radius"), 2.5), *fuzz_range("hub.radius")))
    length = float(np.clip(vary(_default("hub.length"), 2.5), *fuzz_range("hub.length")))
    size = radius / _default("hub.radius")  # the default design's shape, scaled to this hub
    phase = _lerp(take(), *fuzz_range("phase_deg"))

    symmetric, camber = take() < 0.2, take()  # one design in five has a symmetric section
    max_camber = 0.0 if symmetric else _lerp(camber, *fuzz_range("airfoil.max_camber"))
    camber_position = _lerp(take(), *fuzz_range("airfoil.camber_position"))
    thickness = float(
        np.clip(vary(_default("airfoil.thickness"), 8.0), *fuzz_range("airfoil.thickness"))
    )
    camber_normal = take() < 0.5
    pivot = float(np.clip(wild * take(), *fuzz_range("airfoil.pivot")))

    pitch = 360.0 if blades == 1 else 360.0 / blades
    span = (
        pitch * (0.83 if blades > 1 else 100.0 / 360.0) * math.exp(wild * _lerp(take(), -1.0, 0.33))
    )
    span = float(np.clip(span, 10.0, 1.15 * pitch if blades > 1 else 340.0))
    x2 = span * shift(0.25, 0.6)
    x3 = span * shift(0.75, 0.6)
    x4 = span * (-1.0 if take() < 0.15 * wild else 1.0)
    y_span = length - 2.0  # y_L in [0, L - 2] keeps a point between the end faces
    y2 = y_span * shift(3.0 / 18.0, 0.7)
    y3 = y_span * shift(15.0 / 18.0, 0.7)
    y4 = y_span * float(np.clip(shift(1.0, 1.0), 0.0, 1.0))
    inset = radius - radius / 8.0
    z2 = max(vary(22.0 * size, 3.0), -0.9 * inset)
    z3 = max(vary(22.0 * size, 3.0), -0.9 * inset)
    x2, x3 = (float(np.clip(x, -359.0, 359.0)) for x in (x2, x3))
    frame = _choice(take(), "centerline.frame")

    alpha = (
        shift(0.0, 250.0),
        shift(0.0, 250.0),
        shift(0.0, 250.0),
        shift(0.0, 250.0),
        shift(20.0, 90.0),
    )
    # Sections shrink with the span (a shorter blade bends tighter); ends start at half the
    # default's.
    chord = size * min(1.0, span / 100.0)
    scale_x = _positive_quartic(
        (vary(3.0 * chord, 3.0), vary(3.0 * chord, 3.0)),
        vary(5.0 * chord, 3.0),
        shift(0.0, 3.0 * chord),
        0.02 * radius,
    )
    scale_y = _positive_quartic(
        (vary(1.0 * chord, 3.0), vary(1.0 * chord, 3.0)),
        vary(1.5 * chord, 3.0),
        shift(0.0, 1.0 * chord),
        0.02 * radius,
    )

    section_count = round(_lerp(take(), *(sections or fuzz_range("resolution.sections"))))
    point_count = round(_lerp(take(), *(points or fuzz_range("resolution.points"))))
    linear_deflection = _log_lerp(take(), *fuzz_range("export.stl_linear_deflection"))
    angular_deflection = _lerp(take(), *fuzz_range("export.stl_angular_deflection"))
    schema = _choice(take(), "export.step_schema")
    assert next(it, None) is None, (
        "UNIT_DIMENSION does not match the numbers design_dict_from_unit takes"
    )

    return {
        "name": name,
        "blades": blades,
        "phase_deg": phase,
        "hub": {"radius": radius, "length": length},
        "airfoil": {
            "max_camber": max_camber,
            "camber_position": camber_position,
            "thickness": thickness,
            "camber_normal": camber_normal,
            "pivot": pivot,
        },
        "centerline": {"p2": [x2, y2, z2], "p3": [x3, y3, z3], "p4": [x4, y4], "frame": frame},
        "transforms": {
            "angle_of_attack": list(alpha),
            "scale_x": list(scale_x),
            "scale_y": list(scale_y),
        },
        "resolution": {"sections": section_count, "points": point_count},
        "export": {
            "stl_linear_deflection": linear_deflection,
            "stl_angular_deflection": angular_deflection,
            "step_schema": schema,
        },
    }


def design_from_unit(u: Sequence[float], name: str = "fuzz", **kwargs: Any) -> PropellerParameters:
    """:func:`design_dict_from_unit` as validated parameters (may raise ParameterError)."""
    return PropellerParameters.from_dict(design_dict_from_unit(u, name, **kwargs))


def random_design_dict(seed: int, workshop: bool = False, **kwargs: Any) -> dict[str, Any]:
    """The design of ``seed`` as a dict: unit vector from numpy's default_rng(seed); named
    fuzz_<seed>.

    ``workshop``: also draw the workshop features (:func:`workshop_features`) from a stream of
    their own, so the design's other parameters are those of the plain design of ``seed``."""
    rng = np.random.default_rng(seed)
    design = design_dict_from_unit(rng.random(UNIT_DIMENSION), name=f"fuzz_{seed}", **kwargs)
    if workshop:
        for table, values in workshop_features(seed, design["hub"]["radius"]).items():
            if isinstance(values, dict):
                design.setdefault(table, {}).update(values)
            else:
                design[table] = values
    return design


def workshop_features(seed: int, hub_radius_mm: float) -> dict[str, Any]:
    """Issue 13's features, each switched on with probability 1/2: handedness, a bore (10-70 % of
    the hub's diameter) with maybe a D-flat and a set screw, a chamfer, a blunt trailing edge.
    Values outside what the hub or blade allows are drawn on purpose: they must be refused
    cleanly. The root fillet is left out (``scripts/fillet_rate.py`` measures it)."""
    rng = np.random.default_rng([seed, 13])
    on = rng.random(6) < 0.5
    u = rng.random(6)
    hub: dict[str, float] = {}
    if on[0]:
        hub["bore_diameter"] = _lerp(u[0], 0.1, 0.7) * 2.0 * hub_radius_mm
        if on[1]:
            hub["bore_flat_depth"] = _lerp(u[1], 0.05, 0.3) * hub["bore_diameter"]
        if on[2]:  # a set screw needs a bore to reach
            hub["set_screw_diameter"] = _lerp(u[2], 1.5, 4.0)
    if on[3]:
        hub["chamfer"] = _lerp(u[3], 0.1, 1.0)
    features: dict[str, Any] = {"handedness": "ccw" if on[4] else "cw", "hub": hub}
    if on[5]:
        features["airfoil"] = {"trailing_edge_thickness": _lerp(u[5], 0.2, 1.0)}
    return features


def random_design(seed: int, **kwargs: Any) -> PropellerParameters:
    """:func:`random_design_dict` as validated parameters (may raise ParameterError)."""
    return PropellerParameters.from_dict(random_design_dict(seed, **kwargs))


def fuzz_tasks(
    designs: Sequence[dict[str, Any]], write: bool = True, stl: bool = True
) -> list[DesignTask]:
    """Batch tasks for ``designs`` (dicts): built, written to a temporary folder and read back
    (``write``)."""
    return [
        DesignTask(
            str(design.get("name", f"design_{index}")),
            design,
            folder=None,
            write=write,
            stl=stl,
            verify=write,
        )
        for index, design in enumerate(designs)
    ]
