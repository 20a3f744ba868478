"""Off-screen preview pictures (issue 6): exact size, not blank, every blade visible in its colour."""

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
from torus_cad.errors import ParameterError
from torus_cad.kernel.checks import mass_properties
from torus_cad.preview import (
    View,
    _actor,
    loop_area_vectors,
    parse_size,
    preview_mesh,
    propeller_views,
    render_preview,
    render_views,
    write_preview,
)
from torus_cad.propeller import propeller_objects

FAST = ["--set", "resolution.sections=16", "--set", "resolution.points=40"]

#: Floor of the standard deviation of the grey levels (0..1): a blank or flat picture is far below.
PIXEL_STD_FLOOR = 0.08


@pytest.fixture(scope="module")
def objects():
    return propeller_objects(overrides={"resolution.sections": 16, "resolution.points": 40, "name": "preview_fast"})


def _read_png(path) -> np.ndarray:
    with Image.open(path) as image:
        assert image.format == "PNG"
        return np.asarray(image.convert("RGB"), dtype=float) / 255.0


def _hue_pixels(rgb: np.ndarray, colour: tuple[float, float, float]) -> int:
    """Pixels of ``colour``'s hue (any brightness, as shading changes it), saturated enough to count."""
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
        assert _hue_pixels(rgb, blade_color(index, blades)) > 0.004 * grey.size, f"blade {index} not visible"
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
    four = propeller_objects(overrides={"resolution.sections": 12, "resolution.points": 40, "blades": 4})
    rgb = _read_png(write_preview(four, tmp_path / "four.png", size=(800, 400)))
    _assert_a_real_picture(rgb, 4)


def test_preview_mesh_covers_the_solid_and_tags_every_part(objects):
    mesh = preview_mesh(objects.solid, objects.hub, objects.blades)
    assert set(np.unique(mesh.parts)) == {-1, 0, 1, 2}
    corners = mesh.vertices[mesh.triangles]
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1).sum()
    assert area == pytest.approx(mass_properties(objects.solid, 1.0).surface_area_mm2, rel=0.01)
    # Outward normals: the enclosed volume (divergence theorem) is positive and close to the solid's.
    volume = np.einsum("ij,ij->i", corners[:, 0], np.cross(corners[:, 1], corners[:, 2])).sum() / 6.0
    assert volume == pytest.approx(mass_properties(objects.solid, 1.0).volume_mm3, rel=0.01)
    # The preview tessellates a copy: the caller's solid gets no triangulation from it (which would
    # otherwise be reused by a later STL export at a different deflection).
    location = TopLoc_Location()
    assert all(BRep_Tool.Triangulation_s(face.wrapped, location) is None for face in objects.solid.Faces())


def _box_mesh(low: tuple[float, float, float], high: tuple[float, float, float]) -> tuple[np.ndarray, np.ndarray]:
    """An axis-aligned box as 12 outward triangles."""
    x0, y0, z0 = low
    x1, y1, z1 = high
    vertices = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                         [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], dtype=float)
    quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))], dtype=np.int64)
    return vertices, triangles


@pytest.mark.parametrize("near_first", [True, False])
def test_depth_order_a_near_box_covers_a_far_box(near_first):
    """A red box nearer the camera hides a blue one behind it at the picture's centre, whichever is
    drawn first: the renderer has a depth buffer (a painter's algorithm in the wrong order fails)."""
    near = _box_mesh((-1.0, -1.0, 2.0), (1.0, 1.0, 3.0))   # camera on +z: this one is nearer
    far = _box_mesh((-3.0, -3.0, -1.0), (3.0, 3.0, 0.0))    # larger, behind it
    red, blue = np.array([[0.9, 0.1, 0.1]]), np.array([[0.1, 0.1, 0.9]])
    meshes = [(near, red), (far, blue)] if near_first else [(far, blue), (near, red)]
    view = View((0.0, 0.0, 1.0), (0.0, 1.0, 0.0))
    image = render_views(lambda: [_actor(v, t, np.repeat(c, len(t), axis=0)) for (v, t), c in meshes],
                         [view], (200, 200)).astype(float)
    centre, corner = image[100, 100], image[100, 30]   # inside the near box; only the far box there
    assert centre[0] > 2 * centre[2], f"the far box shows through the near one: {centre}"
    assert corner[2] > 2 * corner[0], f"the far box is missing beside the near one: {corner}"


def test_isometric_camera_sees_no_blade_edge_on(objects):
    """Every blade's window (its centerline loop closed through the hub) faces the isometric camera
    by a fifth of its area or more: no blade is drawn as a line or a fragment. The classic (1, 1, 1)
    isometric direction shows one default blade at 6 % of its window, nearly edge-on."""
    geometry = objects.parameters.geometry()
    s = np.linspace(0.0, 1.0, 64)
    areas = loop_area_vectors([geometry.centerline(index).points(s) for index in range(geometry.blades)])
    view = np.array(propeller_views(objects)[0].toward_camera)
    unit = areas / np.linalg.norm(areas, axis=1, keepdims=True)
    classic = np.array([1.0, 1.0, 1.0]) / np.sqrt(3.0)
    assert np.abs(unit @ view).min() > 0.2
    assert np.abs(unit @ view).min() > 3 * np.abs(unit @ classic).min()


@pytest.mark.parametrize(("text", "size"), [("1200x600", (1200, 600)), ("64X64", (64, 64)), (" 800 x 300 ", (800, 300))])
def test_parse_size(text, size):
    assert parse_size(text) == size


@pytest.mark.parametrize("text", ["1200", "x600", "12.5x600", "-5x5", "63x100", "100x9000", "axb", ""])
def test_parse_size_refuses_bad_sizes(text):
    with pytest.raises(ParameterError):
        parse_size(text)


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
    assert main(["build", *FAST, "--no-stl", "--preview", "--preview-size", "400x200", "--out", str(tmp_path)]) == EXIT_OK
    name = "torus_propeller"
    assert sorted(path.name for path in tmp_path.iterdir()) == [f"{name}.json", f"{name}.png", f"{name}.step"]
    assert f"wrote {tmp_path / (name + '.png')}" in capsys.readouterr().out
    assert _read_png(tmp_path / f"{name}.png").shape == (200, 400, 3)
    assert json.loads((tmp_path / f"{name}.json").read_text())["valid"] is True


def test_cli_build_refuses_a_bad_preview_size_and_writes_nothing(tmp_path, capsys):
    assert main(["build", "--preview", "--preview-size", "5x5", "--out", str(tmp_path)]) == EXIT_BAD_INPUT
    assert "--preview-size 5x5: width 5 px is out of range" in capsys.readouterr().err
    assert not any(tmp_path.iterdir())
