"""Joining the blades to the hub: the shared-intersection route, the hub's seam, the fallback.

The shared route (one blade-hub intersection reused for every blade) must give the same
solid as one general fuse of the hub and all blades: same volume at a stated tolerance,
same faces. ``scripts/fuse_routes.py N`` makes the same comparison on N random designs.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import ROUTE_VOLUME_TOLERANCE, VOLUME_PRECISION, assert_same_volume_as_general_fuse
from face_measures import assert_faces_come_from_their_parts
from hypothesis import given, settings
from hypothesis import strategies as st

import torus_cad.kernel.fuse as fuse
from torus_cad.errors import KernelError
from torus_cad.geometry.hub.seam import footprint_arcs_deg, seam_angle_deg
from torus_cad.kernel.checks import is_valid_closed_solid, single_valid_solid
from torus_cad.kernel.fuse import FuseRoute, fuse_all, fuse_pattern
from torus_cad.kernel.hub import hub_solid
from torus_cad.kernel.mass_properties import precise_volume
from torus_cad.propeller import build_propeller
from torus_cad.tolerances import HUB_FOOTPRINT_MARGIN_DEG


def _synthetic_blade(
    root_deg: float, tip_deg: float, width_deg: float, hub_radius: float = 10.0
) -> np.ndarray:
    """(12, 20, 3) points: 3 sections inside the hub at root_deg, 6 far out, 3 inside at tip_deg."""
    sections = []
    for index in range(12):
        inside = index < 3 or index >= 9
        centre = root_deg if index < 6 else tip_deg
        radius = 0.6 * hub_radius if inside else 3.0 * hub_radius
        angles = np.radians(centre + np.linspace(-width_deg / 2, width_deg / 2, 20))
        sections.append(
            np.stack([radius * np.cos(angles), radius * np.sin(angles), np.zeros(20)], axis=1)
        )
    return np.array(sections)


def _angular_distance_deg(a: float, b: float) -> float:
    return abs((a - b + 180.0) % 360.0 - 180.0)


# -- where the seam goes (geometry layer) ----------------------------------------------------------


@settings(max_examples=60, deadline=None, derandomize=True)
@given(
    root=st.floats(-180.0, 180.0),
    span=st.floats(20.0, 160.0),
    width=st.floats(2.0, 40.0),
    blades=st.integers(1, 8),
)
def test_the_seam_misses_every_blade_footprint(root, span, width, blades):
    points = _synthetic_blade(root, root + span, width)
    arcs = footprint_arcs_deg(points, 10.0)
    seam = seam_angle_deg(points, 10.0, blades)
    covered = np.zeros(3600, dtype=bool)
    for low, high in arcs:
        for blade in range(blades):
            start = low + 360.0 * blade / blades
            covered[
                (np.arange(int(np.floor(start * 10)), int(np.ceil((start + high - low) * 10)) + 1))
                % 3600
            ] = True
            if seam is not None:
                middle = (low + high) / 2 + 360.0 * blade / blades
                assert _angular_distance_deg(seam, middle) > (high - low) / 2
    if seam is None:  # only when the footprints close the circle (up to the 0.1 degree scan bins)
        assert covered.mean() > 0.995


def test_footprint_covers_the_sections_inside_the_hub_with_a_margin():
    arcs = footprint_arcs_deg(_synthetic_blade(30.0, 120.0, 10.0), 10.0)
    assert len(arcs) == 2
    (root_low, root_high), (tip_low, tip_high) = arcs
    assert root_low == pytest.approx(25.0 - HUB_FOOTPRINT_MARGIN_DEG)
    assert root_high >= 35.0 + HUB_FOOTPRINT_MARGIN_DEG - 1e-9
    assert tip_low <= 115.0 - HUB_FOOTPRINT_MARGIN_DEG + 1e-9
    assert tip_high == pytest.approx(125.0 + HUB_FOOTPRINT_MARGIN_DEG)


def test_no_seam_when_the_footprints_close_the_circle():
    assert seam_angle_deg(_synthetic_blade(0.0, 90.0, 60.0), 10.0, 8) is None


def test_default_seam_lies_between_blade_roots(default_propeller, default_params):
    seam = seam_angle_deg(
        default_propeller.surface.points, default_params.hub.radius, default_params.blades
    )
    assert seam is not None
    lateral = [face for face in default_propeller.solid.Faces() if face.geomType() == "CYLINDER"]
    assert len(lateral) == 1
    # One outer wire and one hole per blade end; no seam edge through a hole means 2n + 1 wires.
    assert len(lateral[0].Wires()) == 2 * default_params.blades + 1


# -- the kernel's two routes -----------------------------------------------------------------------


def test_hub_seam_angle_moves_the_seam_not_the_solid():
    turned = hub_solid(10.0, 20.0, 75.0)
    assert precise_volume(turned) == pytest.approx(np.pi * 100.0 * 20.0, rel=1e-12)
    seam_edges = [edge for edge in turned.Edges() if edge.geomType() == "LINE"]
    assert len(seam_edges) == 1
    middle = seam_edges[0].Center()
    assert np.degrees(np.arctan2(middle.y, middle.x)) == pytest.approx(75.0, abs=1e-9)


def test_default_takes_the_shared_route_and_equals_the_general_fuse(default_propeller):
    assert default_propeller.fuse_route == FuseRoute.ASSEMBLED  # shared intersection, assembled
    assert_same_volume_as_general_fuse(default_propeller)


def test_the_report_gives_the_route_and_the_spin_as_codes(default_files):
    import json

    report = json.loads(default_files["json"].read_text())
    assert report["fuse_route"] == "assembled"
    assert report["spin_to_push_air_down"] == report["parameters"]["handedness"] == "cw"


@pytest.mark.parametrize(
    "seam_deg, join",
    [(20.0, FuseRoute.GLUED), (90.0, FuseRoute.GLUED), (None, FuseRoute.ASSEMBLED)],
)
def test_any_seam_angle_gives_the_same_solid(default_propeller, seam_deg, join):
    # A seam through a blade root splits that root's patch; the split pieces are shifted on
    # their own and glued. The seam the pipeline picks (None here) lets the shell be assembled.
    params = default_propeller.parameters
    if seam_deg is None:
        seam_deg = seam_angle_deg(
            default_propeller.surface.points, params.hub.radius, params.blades
        )
    hub = hub_solid(params.hub.radius, params.hub.length, seam_deg)
    angles = [360.0 * index / params.blades for index in range(params.blades)]
    fused = fuse_pattern(hub, default_propeller.blades[0], angles)
    solid = single_valid_solid(fused.shape, "the shared route")
    assert fused.route == join
    assert_faces_come_from_their_parts(solid, fused.face_parts, default_propeller)
    assert precise_volume(solid, VOLUME_PRECISION) == pytest.approx(
        precise_volume(default_propeller.solid, VOLUME_PRECISION), rel=ROUTE_VOLUME_TOLERANCE
    )
    assert len(solid.Faces()) == len(default_propeller.solid.Faces())


def test_when_the_shared_route_fails_the_general_fuse_builds_it(light_params, monkeypatch):
    shared = build_propeller(light_params)

    def failing(*_args, **_kwargs):
        raise KernelError("the shared route failed")

    monkeypatch.setattr(fuse, "fuse_pattern", failing)  # the route joined_propeller takes first
    fallback = build_propeller(light_params)
    assert (shared.fuse_route, fallback.fuse_route) == (FuseRoute.ASSEMBLED, FuseRoute.GENERAL)
    assert is_valid_closed_solid(fallback.solid)
    assert precise_volume(fallback.solid, VOLUME_PRECISION) == pytest.approx(
        precise_volume(shared.solid, VOLUME_PRECISION), rel=ROUTE_VOLUME_TOLERANCE
    )


def test_a_wrong_curve_on_the_hub_is_caught_not_shipped(light_params, monkeypatch):
    # Shift every copied intersection curve off its place on the cylinder: the validity check
    # of the shared route must reject it, and the general fuse must take over.

    real_vector = fuse.gp_Vec2d
    monkeypatch.setattr(fuse, "gp_Vec2d", lambda du, dv: real_vector(du + 0.05 if du else du, dv))
    propeller = build_propeller(light_params)
    assert propeller.fuse_route == FuseRoute.GENERAL
    assert is_valid_closed_solid(propeller.solid)


# -- which part each face came from
# ------------------------------------------------------------------


def test_the_default_propeller_knows_each_faces_part(default_propeller):
    assert default_propeller.fuse_route == FuseRoute.ASSEMBLED
    assert_faces_come_from_their_parts(
        default_propeller.solid, default_propeller.face_parts, default_propeller
    )


def test_the_general_fuse_knows_each_faces_part(light_params):
    propeller = build_propeller(light_params)
    fused = fuse_all(propeller.hub, propeller.blades)
    assert fused.route == FuseRoute.GENERAL
    assert_faces_come_from_their_parts(
        single_valid_solid(fused.shape, "the general fuse"), fused.face_parts, propeller
    )


def test_a_mirrored_propeller_keeps_each_faces_part(light_params):
    # handedness ccw mirrors the fused solid (a transformed copy): the faces keep their order.
    mirrored = build_propeller(light_params.with_values({"handedness": "ccw"}))
    assert_faces_come_from_their_parts(mirrored.solid, mirrored.face_parts, mirrored)
