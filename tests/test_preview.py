"""Off-screen preview pictures: exact size, not blank, every blade visible
in its colour, the depth buffer working, no blade seen edge-on."""

from __future__ import annotations

import json

import numpy as np
import pytest
from matplotlib.colors import rgb_to_hsv
from OCP.BRep import BRep_Tool
from OCP.TopLoc import TopLoc_Location
from PIL import Image

from torus_cad.cli import EXIT_BAD_INPUT, EXIT_OK, main
from torus_cad.colors import HUB_COLOR, blade_color
from torus_cad.design.described_geometry import propeller_geometry
from torus_cad.errors import ParameterError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.kernel.mass_properties import mass_properties
from torus_cad.preview.picture import (
    AXIAL_VIEW,
    ISOMETRIC_ELEVATION_DEG,
    SceneMesh,
    View,
    blade_silhouettes,
    oblique_view,
    propeller_mesh,
    render_preview,
    render_views,
    write_preview,
)
from torus_cad.preview.size import parse_size
from torus_cad.propeller import propeller_objects

FAST = ["--set", "resolution.sections=16", "--set", "resolution.points=40"]

#: Floor of the standard deviation of the grey levels (0..1): a blank or flat picture is far below.
PIXEL_STD_FLOOR = 0.08


@pytest.fixture(scope="module")
def objects():
    return propeller_objects(
        overrides={"resolution.sections": 16, "resolution.points": 40, "name": "preview_fast"}
    )


def _read_png(path) -> np.ndarray:
    with Image.open(path) as image:
        assert image.format == "PNG"
        return np.asarray(image.convert("RGB"), dtype=float) / 255.0


def _hue_pixels(rgb: np.ndarray, colour: tuple[float, float, float]) -> int:
    """Pixels of ``colour``'s hue (any brightness, as shading changes it), saturated enough to
    count."""
    hsv = rgb_to_hsv(rgb)
    hue = rgb_to_hsv(np.array(colour))[0]
    distance = np.minimum(abs(hsv[..., 0] - hue), 1.0 - abs(hsv[..., 0] - hue))
    return int(np.count_nonzero((distance < 0.025) & (hsv[..., 1] > 0.45) & (hsv[..., 2] > 0.15)))


def _assert_a_real_picture(rgb: np.ndarray, blades: int) -> None:
    grey = rgb.mean(axis=2)
    assert grey.std() > PIXEL_STD_FLOOR
    drawn = np.count_nonzero(grey < 0.97)  # not background
    assert drawn > 0.08 * grey.size
    for index in range(blades):  # every blade shows, in its own colour
        assert _hue_pixels(rgb, blade_color(index, blades)) > 0.004 * grey.size, (
            f"blade {index} not visible"
        )
    hsv = rgb_to_hsv(rgb)
    hub_like = (hsv[..., 1] < 0.2) & (grey > 0.25) & (grey < 0.9)  # the hub is a neutral grey
    assert np.count_nonzero(hub_like) > 0.01 * grey.size
    assert max(HUB_COLOR) - min(HUB_COLOR) < 0.1


def test_write_preview_gives_the_exact_size_and_a_real_picture(objects, tmp_path):
    path = write_preview(objects, tmp_path / "p.png", size=(640, 360))
    rgb = _read_png(path)
    assert rgb.shape == (360, 640, 3)
    _assert_a_real_picture(rgb, 3)
    assert not list(tmp_path.glob(".*tmp*"))  # the atomic write left no temp file


@pytest.mark.parametrize("size", [(333, 217), (1001, 64), (64, 400)])
def test_render_preview_gives_exactly_the_requested_pixels(objects, size):
    image = render_preview(objects, size=size, title="t")
    assert image.shape == (size[1], size[0], 3)
    assert image.dtype == np.uint8
    assert image[..., :3].std() > 255 * 0.03  # something was drawn even in a thin strip


def test_the_two_views_both_show_the_propeller(objects):
    rgb = render_preview(objects, size=(800, 400)) / 255.0
    for half in (rgb[:, :400], rgb[:, 400:]):  # isometric left, along the axis right
        grey = half.mean(axis=2)
        assert np.count_nonzero(grey < 0.97) > 0.08 * grey.size
        assert grey.std() > PIXEL_STD_FLOOR


def test_a_four_blade_design_shows_four_colours(tmp_path):
    four = propeller_objects(
        overrides={"resolution.sections": 12, "resolution.points": 40, "blades": 4}
    )
    rgb = _read_png(write_preview(four, tmp_path / "four.png", size=(800, 400)))
    _assert_a_real_picture(rgb, 4)


def test_propeller_mesh_covers_the_solid_and_colours_every_part(objects):
    mesh = propeller_mesh(objects.solid, objects.face_parts, len(objects.blades), tolerance=0.02)
    assert set(np.unique(mesh.parts)) == {HUB_PART, 0, 1, 2}
    assert np.allclose(mesh.colors[mesh.parts == HUB_PART], HUB_COLOR, atol=1e-12)
    for blade in range(3):
        assert np.allclose(mesh.colors[mesh.parts == blade], blade_color(blade, 3), atol=1e-12)
    corners = mesh.vertices[mesh.triangles]
    area = (
        0.5
        * np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        ).sum()
    )
    assert area == pytest.approx(mass_properties(objects.solid, 1.0).surface_area_mm2, rel=0.01)
    # Outward normals: the enclosed volume (divergence theorem) is positive and close to the
    # solid's.
    volume = (
        np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum() / 6.0
    )
    assert volume == pytest.approx(mass_properties(objects.solid, 1.0).volume_mm3, rel=0.01)
    # The preview tessellates a copy: the caller's solid gets no triangulation from it (which would
    # otherwise be reused by a later STL export at a different deflection).
    location = TopLoc_Location()
    assert all(
        BRep_Tool.Triangulation_s(face.wrapped, location) is None for face in objects.solid.Faces()
    )


def test_propeller_mesh_refuses_parts_that_do_not_match_the_faces(objects):
    with pytest.raises(ValueError, match="face_parts"):
        propeller_mesh(objects.solid, objects.face_parts[:-1], len(objects.blades), tolerance=0.05)


# -- the renderer: depth order, and the view that shows every blade ------------------------------


def _box(
    low: tuple[float, float, float], high: tuple[float, float, float]
) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned box as 8 vertices and 12 outward (counter-clockwise) triangles."""
    x, y, z = zip(low, high, strict=True)
    vertices = np.array(
        [[x[i], y[j], z[k]] for i in (0, 1) for j in (0, 1) for k in (0, 1)], dtype=float
    )
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    return vertices, triangles


@pytest.mark.parametrize("near_first", [True, False])
def test_the_near_box_hides_the_far_box_whatever_the_drawing_order(near_first):
    # The near (red) box covers the left half of the far (blue) box, seen along -z. Triangles are
    # drawn in order: with the near box's first, a renderer without a depth test would let the
    # far box paint over it; with the far box's first, a renderer that drew back faces or ignored
    # the near box would fail the other way.
    boxes = [
        (_box((-1.0, -1.0, 2.0), (0.2, 1.0, 3.0)), (0.9, 0.1, 0.1), 0),  # near, red
        (_box((-1.0, -1.0, -3.0), (1.0, 1.0, -2.0)), (0.1, 0.1, 0.9), 1),
    ]  # far, blue
    if not near_first:
        boxes.reverse()
    (first_vertices, first_triangles), first_colour, first_part = boxes[0]
    (second_vertices, second_triangles), second_colour, second_part = boxes[1]
    scene = SceneMesh(
        np.concatenate([first_vertices, second_vertices]),
        np.concatenate([first_triangles, second_triangles + len(first_vertices)]),
        np.array([first_colour] * len(first_triangles) + [second_colour] * len(second_triangles)),
        np.array([first_part] * len(first_triangles) + [second_part] * len(second_triangles)),
    )
    image = render_views(scene, [View((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), "")], (200, 200)).astype(
        float
    )
    # x in [-1, 1] spans the middle of the 200 px view (the camera frames the scene with a margin).
    overlap, far_only = image[100, 70], image[100, 150]
    assert overlap[0] > 2.0 * overlap[2], (
        f"the near red box should cover the far blue one, got {overlap}"
    )
    assert far_only[2] > 2.0 * far_only[0], (
        f"the far blue box should show beside the near one, got {far_only}"
    )


def _worst_blade_fraction(mesh: SceneMesh, direction: np.ndarray, reference: np.ndarray) -> float:
    return float((blade_silhouettes(mesh, direction[None, :])[:, 0] / reference).min())


def test_the_oblique_view_shows_every_blade_of_the_default(default_propeller):
    mesh = propeller_mesh(default_propeller.solid, default_propeller.face_parts, 3, tolerance=0.1)
    # the loops open upward
    largest = blade_silhouettes(mesh, np.array([[0.0, 0.0, 1.0]]))[:, 0].max()
    view = oblique_view(mesh)
    chosen = _worst_blade_fraction(mesh, np.array(view.toward_camera), largest)
    # The classic isometric corner (elevation 35.26°, azimuth 45°) shows one blade nearly edge-on.
    e, a = np.radians(ISOMETRIC_ELEVATION_DEG), np.radians(45.0)
    corner = _worst_blade_fraction(
        mesh, np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)]), largest
    )
    assert chosen > 0.5 and chosen > 1.5 * corner
    assert view.toward_camera[2] > 0.5  # from above
    assert AXIAL_VIEW.toward_camera == (0.0, 0.0, 1.0)


@pytest.mark.parametrize(
    ("text", "size"), [("1200x600", (1200, 600)), ("64X64", (64, 64)), (" 800 x 300 ", (800, 300))]
)
def test_parse_size(text, size):
    assert parse_size(text) == size


@pytest.mark.parametrize(
    "text",
    [
        "1200",
        "x600",
        "12.5x600",
        "-5x5",
        "63x100",
        "100x9000",
        "axb",
        "",
        # was an internal error
        pytest.param("9" * 5001 + "x600", id="5001_digits"),
    ],
)
def test_parse_size_refuses_bad_sizes(text):
    with pytest.raises(ParameterError) as refused:
        parse_size(text)
    assert len(str(refused.value)) < 200  # a long size is cut in the message


# -- command line ---------------------------------------------------------------------------------


def test_cli_preview_writes_the_requested_picture(tmp_path, capsys):
    out = tmp_path / "pictures" / "prop.png"
    assert main(["preview", *FAST, "--out", str(out), "--size", "480x320"]) == EXIT_OK
    captured = capsys.readouterr()
    assert f"wrote {out}" in captured.out
    assert captured.err == ""  # no progress lines when stderr is not a terminal
    rgb = _read_png(out)
    assert rgb.shape == (320, 480, 3)
    _assert_a_real_picture(rgb, 3)


def test_cli_preview_default_path_and_quiet(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["preview", *FAST, "--set", "name=quiet_one", "--size", "200x100", "-q"]) == EXIT_OK
    assert capsys.readouterr() == ("", "")
    assert _read_png(tmp_path / "step_out" / "quiet_one.png").shape == (100, 200, 3)


@pytest.mark.parametrize("size", ["10x10", "wide", "100x"])
def test_cli_preview_refuses_a_bad_size_before_building(tmp_path, size, capsys):
    out = tmp_path / "p.png"
    assert main(["preview", "--out", str(out), "--size", size]) == EXIT_BAD_INPUT
    err = capsys.readouterr().err
    assert err.startswith("torus-cad: error: --size ") and size in err
    assert not out.exists()


def test_cli_build_preview_writes_the_picture_beside_the_files(tmp_path, capsys):
    assert (
        main(
            [
                "build",
                *FAST,
                "--no-stl",
                "--preview",
                "--preview-size",
                "400x200",
                "--out",
                str(tmp_path),
            ]
        )
        == EXIT_OK
    )
    name = "torus_propeller"
    assert sorted(path.name for path in tmp_path.iterdir()) == [
        f"{name}.json",
        f"{name}.png",
        f"{name}.step",
        f"{name}_sections.csv",
        f"{name}_sections.png",
    ]
    assert f"wrote {tmp_path / (name + '.png')}" in capsys.readouterr().out
    assert _read_png(tmp_path / f"{name}.png").shape == (200, 400, 3)
    assert json.loads((tmp_path / f"{name}.json").read_text())["valid"] is True


def test_cli_build_refuses_a_bad_preview_size_and_writes_nothing(tmp_path, capsys):
    assert (
        main(["build", "--preview", "--preview-size", "5x5", "--out", str(tmp_path)])
        == EXIT_BAD_INPUT
    )
    assert "--preview-size 5x5: width 5 px is out of range" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_the_oblique_view_faces_every_blades_window(default_propeller):
    # A second measure of "not edge-on": each blade's window (its centerline loop closed through
    # the hub) faces the camera by a fifth of its area or more, where the classic (1, 1, 1)
    # isometric direction shows one default blade at ~6 % of its window, nearly as a line.
    geometry = propeller_geometry(default_propeller.parameters)
    s = np.linspace(0.0, 1.0, 64)
    loops = [geometry.centerline(index).points(s) for index in range(geometry.blades)]
    areas = np.array(
        [0.5 * np.cross(loop, np.roll(loop, -1, axis=0)).sum(axis=0) for loop in loops]
    )
    unit = areas / np.linalg.norm(areas, axis=1, keepdims=True)
    mesh = propeller_mesh(default_propeller.solid, default_propeller.face_parts, 3, tolerance=0.1)
    view = np.array(oblique_view(mesh).toward_camera)
    classic = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    assert np.abs(unit @ view).min() > 0.2
    assert np.abs(unit @ view).min() > 3 * np.abs(unit @ classic).min()


def test_a_filleted_propeller_shows_every_part(tmp_path):
    # The root fillet's build reports each face's part from the fillet's history.
    filleted = propeller_objects("examples/workshop_fillet.toml")
    _assert_a_real_picture(
        _read_png(write_preview(filleted, tmp_path / "fillet.png", size=(800, 400))), 3
    )


def test_build_preview_and_preview_show_the_same_picture(tmp_path):
    assert (
        main(["build", "--preview", "--no-stl", "-q", "--out", str(tmp_path / "built")]) == EXIT_OK
    )
    assert main(["preview", "-q", "--out", str(tmp_path / "preview.png")]) == EXIT_OK
    built = np.asarray(
        Image.open(tmp_path / "built" / "torus_propeller.png").convert("RGB"), dtype=int
    )
    alone = np.asarray(Image.open(tmp_path / "preview.png").convert("RGB"), dtype=int)
    assert built.shape == alone.shape
    # the same camera: rendering noise only
    assert (np.abs(built - alone).sum(axis=-1) > 30).mean() < 0.01
