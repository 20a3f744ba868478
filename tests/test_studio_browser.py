"""The studio in a real browser: headless Chromium (Debian's chromium + chromium-driver, driven by
selenium) against ``python -m torus_cad studio --port 0`` started as a separate process."""

from __future__ import annotations

import colorsys
import os
import subprocess
import sys
import threading
import time
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from studio_driver import (
    CHROMEDRIVER,
    CHROMIUM,
    StudioPage,
    StudioProcess,
    chromium,
    wait_for_download,
)

from torus_cad.parameters import PropellerParameters, parameter_specs
from torus_cad.studio.layout import field_id

REPO = Path(__file__).resolve().parent.parent
SCREENSHOT = REPO / "docs" / "images" / "studio.png"  # the README's picture of the studio
UPDATE_IMAGES = "TORUS_CAD_UPDATE_IMAGES"  # =1: the screenshot test rewrites SCREENSHOT


def screenshot_path(scratch: Path) -> Path:
    """Where the screenshot test saves the page: the README's picture with
    TORUS_CAD_UPDATE_IMAGES=1, else ``scratch`` (running the tests leaves the git tree clean)."""
    return SCREENSHOT if os.environ.get(UPDATE_IMAGES) == "1" else scratch / SCREENSHOT.name


def test_the_readme_screenshot_is_rewritten_only_when_asked(monkeypatch, tmp_path):
    monkeypatch.delenv(UPDATE_IMAGES, raising=False)
    assert screenshot_path(tmp_path) == tmp_path / "studio.png"
    monkeypatch.setenv(UPDATE_IMAGES, "0")
    assert screenshot_path(tmp_path) == tmp_path / "studio.png"
    monkeypatch.setenv(UPDATE_IMAGES, "1")
    assert screenshot_path(tmp_path) == SCREENSHOT


@pytest.fixture(scope="module")
def studio():
    if not (CHROMIUM.exists() and CHROMEDRIVER.exists()):
        pytest.fail(
            "the studio's browser tests need Debian's chromium and chromium-driver "
            "(apt-get install chromium chromium-driver; .ci/run installs them)"
        )
    with StudioProcess(cwd=REPO) as process:
        yield process


@pytest.fixture(scope="module")
def downloads(tmp_path_factory) -> Path:
    return tmp_path_factory.mktemp("downloads")


@pytest.fixture(scope="module")
def page(studio, downloads):
    with chromium(downloads) as driver:
        page = StudioPage(driver, studio.url)
        page.wait_idle()
        yield page


def _volume_text(design: PropellerParameters) -> str:
    """The volume readout the page should show for ``design``: the same build, in this process."""
    from torus_cad.propeller import build_propeller

    return f"{build_propeller(design).mass_properties().volume_mm3:.2f} mm³"


def test_the_studio_serves_this_machine_only_and_says_so(studio):
    assert studio.url.startswith("http://127.0.0.1:")
    assert "only this machine can connect" in "".join(studio.output)


def test_page_shows_every_parameter_and_the_default_propeller(page):
    page.open_all_groups()
    inputs = [field_id(spec.key) + ("-0" if spec.length else "") for spec in parameter_specs()]
    page.wait(
        lambda: all(page.exists(element) for element in inputs), "an input for every parameter"
    )
    page.change("blades", "3")
    assert page.text("readout-volume") == _volume_text(PropellerParameters())
    assert page.text("readout-valid") == "valid: 1 closed solid"


#: Seconds to wait for the vortex solver's numbers: one point is ~5 s of CPU, several times that on
#: a loaded machine.
PERFORMANCE_WAIT_S = 120.0


def _thrust_at(page, rpm: str) -> float:
    """The thrust readout, N, once the numbers of ``rpm`` (and the loading plot) are shown."""
    page.wait(
        lambda: (
            page.text("readout-point").startswith(f"at {rpm} rpm, 0 m/s")
            and page.text("readout-thrust").endswith(" N")
            and page.exists("performance-plot")
        ),
        f"the vortex solver's numbers at {rpm} rpm",
        PERFORMANCE_WAIT_S,
    )
    return float(page.text("readout-thrust").removesuffix(" N"))


def test_the_vortex_solvers_thrust_shows_for_the_default_design_and_follows_the_rpm(page):
    page.change("blades", "3")  # the default design
    thrust_10k = _thrust_at(page, "10000")
    assert (
        page.text("readout-power").endswith(" W") and 0.0 < float(page.text("readout-merit")) < 1.0
    )
    assert "vortex solver" in page.text("performance-label")
    # typed key by key: each keystroke supersedes the solve before
    page.set_field("perf_rpm", "12000")
    assert _thrust_at(page, "12000") > 1.2 * thrust_10k  # thrust ~ rpm^2
    page.set_field("perf_rpm", "99999")
    page.wait(
        lambda: (
            "rpm = 99999 is out of range; allowed [0, " in page.message_of(field_id("perf_rpm"))
        ),
        "the rpm's refusal",
    )
    page.set_field("perf_rpm", "10000")
    assert _thrust_at(page, "10000") == thrust_10k


def test_four_blades_change_the_volume_readout(page):
    page.change("blades", "3")
    three_blades = page.text("readout-volume")
    page.start_latency_probe()
    page.change("blades", "4")
    assert page.text("readout-volume") != three_blades
    assert page.text("readout-volume") == _volume_text(
        PropellerParameters().with_values({"blades": 4})
    )
    latencies = page.latencies_ms()
    print(
        f"\nstudio latency in the browser, 3 -> 4 blades: preview {latencies['preview']:.0f} ms, "
        f"exact solid {latencies['exact']:.0f} ms "
        f"({page.text('timings')}; {page.text('preview-detail')})"
    )


def test_mass_follows_the_density_entered(page):
    page.change("blades", "4")
    volume_mm3 = float(page.text("readout-volume").split()[0])
    page.set_field("density_g_cm3", "7.85")  # steel
    page.wait(
        lambda: page.text("readout-mass") == f"{volume_mm3 * 7.85e-3:.3f} g", "the steel mass"
    )
    page.set_field("density_g_cm3", "0")
    page.wait(
        lambda: (
            "density = 0 is out of range; allowed (0, 25] g/cm^3"
            in page.message_of(field_id("density_g_cm3"))
        ),
        "the density's refusal",
    )
    page.set_field("density_g_cm3", "1.24")
    page.wait(lambda: page.text("readout-mass") == f"{volume_mm3 * 1.24e-3:.3f} g", "the PLA mass")


@pytest.mark.parametrize(
    ("radius", "reason"),
    [
        ("0.1", "hub.radius = 0.1 is out of range; allowed [0.5, 1000] mm"),
        ("3", "the blade's root (s = 0) section leaves the hub's inset"),
    ],
)
def test_a_refused_value_shows_the_reason_and_keeps_the_last_good_propeller(page, radius, reason):
    page.change("hub.radius", "10")
    volume = page.text("readout-volume")
    page.set_field("hub.radius", radius)  # typed key by key: "0.1" passes through "0" (refused too)
    page.wait(lambda: reason in page.field_message("hub.radius"), "the reason under the field")
    assert reason in page.text("refusal") and page.text("status") == "refused"
    assert page.text("readout-volume") == volume  # the last good propeller stays, downloadable
    assert page.element("download-step").is_enabled()
    page.change("hub.radius", "10")
    assert page.field_message("hub.radius").count(reason) == 0


def test_a_menu_choice_rebuilds_the_mirror_image(page):
    page.change("blades", "4")
    volume = page.text("readout-volume")
    before = page.stamp("exact-stamp")
    page.choose("handedness", "ccw")
    page.wait(
        lambda: page.stamp("exact-stamp") > before and page.idle(), "the mirror image's exact solid"
    )
    assert page.text("readout-volume") == volume  # a mirror image has the same volume
    before = page.stamp("exact-stamp")
    page.choose("handedness", "cw")
    page.wait(
        lambda: page.stamp("exact-stamp") > before and page.idle(), "the clockwise propeller again"
    )


def test_orbiting_turns_the_view_and_a_change_keeps_the_viewpoint(page):
    page.change("hub.length", "20")
    time.sleep(1.0)  # the browser draws asynchronously
    before = page.view_pixels()
    page.drag_view(150, 60)
    time.sleep(1.0)
    orbited = page.view_pixels()
    assert (np.abs(orbited - before).sum(axis=2) > 30).mean() > 0.05  # the propeller turned
    page.change("hub.length", "22")
    time.sleep(1.0)
    changed = page.view_pixels()
    page.change("hub.length", "20")
    differs = (np.abs(changed - orbited).sum(axis=2) > 30).mean()
    # still seen from the new side
    assert differs < (np.abs(changed - before).sum(axis=2) > 30).mean() / 2
    page.click("reset-view")


def test_downloaded_step_is_one_valid_solid_with_the_readout_volume(page, downloads):
    from torus_cad.kernel.checks import is_valid_closed_solid
    from torus_cad.kernel.mass_properties import precise_volume
    from torus_cad.kernel.step_readback import read_step

    page.change("blades", "4")
    page.click("download-step")
    shape = read_step(wait_for_download(downloads, ".step"))
    assert len(shape.Solids()) == 1 and is_valid_closed_solid(shape.Solids()[0])
    assert f"{precise_volume(shape):.2f} mm³" == page.text("readout-volume")


def test_downloaded_stl_is_watertight_with_the_readout_volume(page, downloads):
    from conftest import read_binary_stl

    page.change("blades", "4")
    page.click("download-stl")
    triangles = read_binary_stl(wait_for_download(downloads, ".stl")).astype(float)
    vertices, index = np.unique(triangles.reshape(-1, 3), axis=0, return_inverse=True)
    faces = index.reshape(-1, 3)
    edges = np.sort(faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
    # closed: every edge used twice
    assert np.all(np.unique(edges, axis=0, return_counts=True)[1] == 2)
    a, b, c = (vertices[faces[:, k]] for k in range(3))
    volume_mm3 = float(page.text("readout-volume").split()[0])
    assert np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0 == pytest.approx(
        volume_mm3, rel=0.01
    )


def test_downloaded_design_builds_unchanged_with_the_cli(page, downloads, tmp_path):
    page.change("blades", "4")
    page.click("download-toml")
    design = wait_for_download(downloads, ".toml")
    assert PropellerParameters.from_toml(design) == PropellerParameters().with_values({"blades": 4})
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "torus_cad",
            "build",
            str(design),
            "--out",
            str(tmp_path),
            "--no-stl",
            "-q",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert (tmp_path / "torus_propeller.step").stat().st_size > 0


def test_screenshot_of_the_studio(page, tmp_path):
    """The README's picture (docs/images/studio.png, rewritten only with TORUS_CAD_UPDATE_IMAGES=1):
    the page with a four-blade propeller, each blade in its colour."""
    from PIL import Image

    from torus_cad.colors import blade_color

    readme_picture = SCREENSHOT.read_bytes() if SCREENSHOT.exists() else None
    path = screenshot_path(tmp_path)
    page.change("blades", "4")
    if not page.element("toggle-sections").is_selected():
        page.click("toggle-sections")
    page.wait(lambda: page.element("toggle-sections").is_selected(), "the section curves")
    # the browser draws the curves after the toggle's round trip; nothing on the page says when
    time.sleep(2.0)
    page.screenshot(path)
    if path != SCREENSHOT:
        assert (SCREENSHOT.read_bytes() if SCREENSHOT.exists() else None) == readme_picture
    with Image.open(path) as picture:
        assert picture.format == "PNG"
        width, height = page.driver.execute_script(
            "return [window.innerWidth * devicePixelRatio, window.innerHeight * devicePixelRatio]"
        )
        assert picture.size == (round(width), round(height))  # the whole window of the page
    box = page.element("view").rect
    image = (
        Image.open(path)
        .convert("HSV")
        .crop(
            (
                int(box["x"]),
                int(box["y"]),
                int(box["x"] + box["width"]),
                int(box["y"] + box["height"]),
            )
        )
    )
    hue, saturation, value = np.moveaxis(np.asarray(image, dtype=float) / 255.0, 2, 0)
    for blade in range(4):  # every blade is drawn in its own colour (lit and shaded: compare hues)
        blade_hue = colorsys.rgb_to_hsv(*blade_color(blade, 4))[0]
        near = (
            (np.abs((hue - blade_hue + 0.5) % 1.0 - 0.5) < 0.03)
            & (saturation > 0.5)
            & (value > 0.25)
        )
        assert near.sum() > 1000, f"blade {blade}'s colour is missing from the 3D view"
    grey = (saturation < 0.1) & (value > 0.3) & (value < 0.8)  # the hub
    assert grey.sum() > 5000


def test_an_uploaded_design_goes_through_the_cli_validation(page, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("blades = 5\n[hub]\nradius = 0.1\n")
    cli = subprocess.run(
        [sys.executable, "-m", "torus_cad", "build", str(bad), "--out", str(tmp_path / "out")],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert cli.returncode == 2
    cli_reason = cli.stderr.strip().removeprefix("torus-cad: error: ")
    volume = page.text("readout-volume")
    page.element("upload").send_keys(str(bad))
    page.wait(lambda: cli_reason in page.message_of("upload"), "the upload's refusal")
    assert page.text("readout-volume") == volume

    # a design from the page may not make the server read a file
    remote_file = tmp_path / "remote_file.toml"
    remote_file.write_text('[airfoil]\nfile = "/etc/hostname"\n')
    page.element("upload").send_keys(str(remote_file))
    page.wait(
        lambda: "may name only files uploaded with it" in page.message_of("upload"),
        "the file path's refusal",
    )

    good = tmp_path / "five.toml"
    good.write_text('blades = 5\n[export]\nformats = ["step", "stl", "3mf"]\n')
    before = page.stamp("exact-stamp")
    page.element("upload").send_keys(str(good))
    page.wait(lambda: page.field_value("blades") == "5", "the uploaded design in the panel")
    # the stamp first: the old build's page is idle too, until the new build clears its files
    page.wait(
        lambda: page.stamp("exact-stamp") > before and page.idle(), "the uploaded design's solid"
    )
    design = PropellerParameters.from_toml(good)
    assert page.text("readout-volume") == _volume_text(design)


def test_every_file_the_build_writes_is_downloadable(page, downloads):
    import csv

    import trimesh

    page.wait(lambda: page.field_value("blades") == "5", "the 3MF design of the upload test")
    page.wait_idle()
    page.click("download-3mf")
    mesh = trimesh.load(wait_for_download(downloads, ".3mf"), force="mesh")
    assert mesh.is_watertight
    volume_mm3 = float(page.text("readout-volume").split()[0])
    assert mesh.volume == pytest.approx(volume_mm3, rel=0.01)
    page.click("download-sections_csv")
    with wait_for_download(downloads, "_sections.csv").open(newline="") as table:
        rows = list(csv.reader(line for line in table if not line.startswith("#")))
    # a header, then one row per section
    assert len(rows) - 1 == PropellerParameters().resolution.sections


# -- hostile uploads: refused, nothing of the server's files shown, the server answers everyone
# ----------

SECRET = "alice:$6$SECRETHASHxyz:19000:0:99999:7:::"


def _coordinates(points: int, digits: int = 5, huge: bool = False) -> str:
    u = 0.5 * (1.0 - np.cos(np.linspace(0.0, np.pi, points // 2)))
    upper = [(x, 0.06 * np.sin(np.pi * x)) for x in u[::-1]]
    lower = [(x, -0.04 * np.sin(np.pi * x)) for x in u[1:]]
    lines = ["foil"] + [f"{x:.{digits}f} {y:.{digits}f}" for x, y in upper + lower]
    if huge:
        lines[3] = "1e308 0.01"
    return "\n".join(lines) + "\n"


def _hostile_uploads(folder: Path) -> list[tuple[str, list[Path], str]]:
    """(case, the files chosen together in the page, what the refusal must say)."""
    secret = folder / "shadow"
    secret.write_text(f"root:x:0:0:root:/root:/bin/bash\n{SECRET}\n")
    os.mkfifo(folder / "pipe.dat")

    def design(name: str, text: str | bytes, *others: tuple[str, str]) -> list[Path]:
        case = folder / name.removesuffix(".toml")
        case.mkdir()
        path = case / name
        path.write_bytes(text if isinstance(text, bytes) else text.encode())
        for other, content in others:
            (case / other).write_text(content)
        return [path, *(case / other for other, _ in others)]

    only = "may name only files uploaded with it"
    return [
        (
            "byte-order mark + /etc/shadow",
            design("bom.toml", b'\xef\xbb\xbf[airfoil]\nfile = "/etc/shadow"\n'),
            only,
        ),
        ("a private file", design("private.toml", f'[airfoil]\nfile = "{secret}"\n'), only),
        ("../../etc/passwd", design("dots.toml", '[airfoil]\nfile = "../../etc/passwd"\n'), only),
        ("~/.ssh/id_ed25519", design("home.toml", '[airfoil]\nfile = "~/.ssh/id_ed25519"\n'), only),
        ("a named pipe", design("fifo.toml", f'[airfoil]\nfile = "{folder / "pipe.dat"}"\n'), only),
        ("/dev/zero", design("zero.toml", '[airfoil]\nfile = "/dev/zero"\n'), only),
        (
            "an uploaded private file",
            design(
                "copied.toml", '[airfoil]\nfile = "foil.dat"\n', ("foil.dat", secret.read_text())
            ),
            "airfoil file 'foil.dat' line 2: expected two numbers",
        ),
        (
            "94,000 points",
            design(
                "huge.toml", '[airfoil]\nfile = "foil.dat"\n', ("foil.dat", _coordinates(94_000))
            ),
            "more than 20,000 points",
        ),
        (
            "a 1e308 coordinate",
            design(
                "big.toml",
                '[airfoil]\nfile = "foil.dat"\n',
                ("foil.dat", _coordinates(100, huge=True)),
            ),
            "line 4: a coordinate is out of range",
        ),
        (
            "500-deep nesting",
            design("deep.toml", "[hub]\nradius = " + "[" * 500 + "]" * 500 + "\n"),
            "hub.radius is nested more than",
        ),
        (
            "a 5001-digit integer",
            design("digits.toml", "blades = " + "9" * 5001 + "\n"),
            "blades holds a number of 5001 digits",
        ),
        (
            "an oversized design",
            design("large.toml", "blades = 3\n" + "# padding\n" * 30_000),
            "at most 262,144 bytes",
        ),
    ]


class _Prober:
    """Another client: fetches the page again and again while an upload is handled; the slowest
    answer, s."""

    def __init__(self, url: str) -> None:
        self.url, self.slowest_s, self.answers = url, 0.0, 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def _run(self) -> None:
        while not self._stop.is_set():
            start = time.perf_counter()
            with urllib.request.urlopen(self.url, timeout=30) as response:
                assert response.status == 200 and response.read()
            self.slowest_s = max(self.slowest_s, time.perf_counter() - start)
            self.answers += 1
            time.sleep(0.05)

    def __enter__(self) -> _Prober:
        self._thread.start()
        return self

    def __exit__(self, *_: object) -> None:
        self._stop.set()
        self._thread.join(timeout=60)


def test_hostile_uploads_are_refused_and_the_server_keeps_answering(page, studio, tmp_path):
    """Every attack of the issue, through the page's own upload: refused with its reason, no content
    of any server file on the page, and another client answered within a second while the upload is
    handled."""
    page.change("blades", "3")
    volume = page.text("readout-volume")
    for case, files, reason in _hostile_uploads(tmp_path):
        with _Prober(studio.url) as prober:
            start = time.perf_counter()
            page.element("upload").send_keys("\n".join(str(path) for path in files))
            page.wait(
                lambda reason=reason: reason in page.message_of("upload"), f"the refusal of {case}"
            )
            refused_s = time.perf_counter() - start
            time.sleep(0.3)
        print(
            f"\n{case}: refused on the page after "
            f"{refused_s:.2f} s; another client's slowest answer "
            f"{prober.slowest_s * 1000:.0f} ms ({prober.answers} answers)"
        )
        assert prober.answers > 0 and prober.slowest_s < 1.0, (
            f"{case}: another client waited {prober.slowest_s:.2f} s"
        )
        source = page.driver.page_source
        assert "SECRETHASH" not in source and "/bin/bash" not in source, case
        assert page.text("readout-volume") == volume, case  # the propeller on screen stays
    # valid, at the largest resolution: drawn coarser, built in its bounded process
    largest = tmp_path / "largest.toml"
    largest.write_text("blades = 12\n[resolution]\nsections = 400\npoints = 2000\n")
    with _Prober(studio.url) as prober:
        page.element("upload").send_keys(str(largest))
        page.wait(lambda: "opened largest.toml" in page.message_of("upload"), "the largest design")
        page.wait(lambda: page.text("status") in ("preview", "exact"), "its preview")
        time.sleep(1.0)
    assert prober.answers > 0 and prober.slowest_s < 1.0, (
        f"another client waited {prober.slowest_s:.2f} s"
    )
    print(
        "\nthe largest resolution: another client's "
        f"slowest answer {prober.slowest_s * 1000:.0f} ms"
    )
    plain = tmp_path / "plain.toml"  # and the page goes on: the largest build is superseded
    plain.write_text("blades = 3\n")
    before = page.stamp("exact-stamp")
    page.element("upload").send_keys(str(plain))
    page.wait(
        lambda: page.stamp("exact-stamp") > before and page.idle(), "the plain design's solid"
    )
    assert page.text("readout-volume") == volume


def test_a_design_uploaded_with_its_coordinate_file_is_built_from_it(page, tmp_path):
    airfoils = REPO / "examples" / "airfoils"
    (tmp_path / "clarky.dat").write_bytes((airfoils / "clarky.dat").read_bytes())
    design = tmp_path / "clark.toml"
    design.write_text('blades = 3\n[airfoil]\nfile = "clarky.dat"\n')
    before = page.stamp("exact-stamp")
    page.element("upload").send_keys(f"{design}\n{tmp_path / 'clarky.dat'}")
    page.wait(lambda: "opened clark.toml" in page.message_of("upload"), "the upload")
    page.wait(
        lambda: page.stamp("exact-stamp") > before and page.idle(), "the uploaded design's solid"
    )
    assert page.text("readout-volume") == _volume_text(PropellerParameters.from_toml(design))
