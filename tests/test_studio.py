"""The studio's parts without a browser: the panel from the schema, the preview, the exact build's
tessellation and the worker process that builds it."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys

import numpy as np
import pytest

from torus_cad import PropellerParameters
from torus_cad.errors import GeometryError, ParameterError
from torus_cad.geometry.blade.propeller_geometry import HUB_PART
from torus_cad.geometry.blade.triangle_mesh import TriangleMesh
from torus_cad.studio.panel import (
    FieldKind,
    design_from_state,
    field_of_message,
    schema_groups,
    state_name,
    state_values,
)
from torus_cad.studio.scene import cylinder_mesh, preview_scene


@pytest.fixture(scope="module")
def groups():
    return schema_groups()


def _closed(mesh) -> bool:
    return TriangleMesh(mesh.vertices, mesh.triangles).is_watertight()


# -- panel
# -------------------------------------------------------------------------------------------


def test_panel_has_one_field_per_schema_parameter_grouped_by_toml_table(groups):
    from torus_cad.parameters import parameter_specs

    specs = parameter_specs()
    assert [field.key for group in groups for field in group.fields] == [spec.key for spec in specs]
    tables = [
        key for key, value in PropellerParameters().to_dict().items() if isinstance(value, dict)
    ]
    assert [group.section for group in groups] == ["", *tables]
    fields = {field.key: field for group in groups for field in group.fields}
    radius = fields["hub.radius"]
    assert (radius.unit, radius.low, radius.high, radius.kind) == (
        "mm",
        0.5,
        1000.0,
        FieldKind.NUMBER,
    )
    assert radius.range_text == "[0.5, 1000] mm"
    assert fields["centerline.p2"].element_units == ("deg", "mm", "mm")
    assert fields["centerline.frame"].choices == ("frenet", "rotation_minimizing")
    assert fields["airfoil.camber_normal"].kind is FieldKind.BOOLEAN


def test_file_paths_are_read_only_in_the_panel(groups):
    fields = {field.key: field for group in groups for field in group.fields}
    paths = ("airfoil.file", "conventional.stations_file")
    # the server would read them: never taken from the page
    assert all(fields[key].read_only for key in paths)
    assert not any(field.read_only for key, field in fields.items() if key not in paths)
    assert fields["export.formats"].kind is FieldKind.CHOICES


def _bored_schema():
    """The schema with one more parameter, declared the way torus_cad/parameters/design.py does."""
    from pydantic import Field

    from torus_cad.parameters.design import Hub
    from torus_cad.parameters.schema import param

    class BoredHub(Hub):
        """Cylinder on the z axis, with a bore."""

        bore_diameter: float = param(
            0.0, unit="mm", ge=0.0, le=500.0, doc="coaxial through-bore; 0 = solid hub"
        )

    class BoredPropeller(PropellerParameters):
        """A propeller with a bored hub."""

        hub: BoredHub = Field(default_factory=BoredHub)

    return BoredPropeller


def test_a_parameter_added_to_the_schema_appears_in_the_panel_by_itself():
    from trame.app import get_server
    from trame.ui.vuetify3 import SinglePageLayout

    from torus_cad.parameters.schema import iter_parameter_specs, section_docs
    from torus_cad.studio.layout import parameter_panel
    from torus_cad.studio.panel import panel_groups

    model = _bored_schema()
    groups = panel_groups(iter_parameter_specs(model), section_docs(model))
    hub = next(group for group in groups if group.section == "hub")
    bore = next(field for field in hub.fields if field.key == "hub.bore_diameter")
    assert (bore.unit, bore.low, bore.high, bore.kind) == ("mm", 0.0, 500.0, FieldKind.NUMBER)
    assert bore.slider == (0.0, 500.0, 5.0)
    assert "coaxial through-bore" in bore.hint

    values = state_values(model().to_dict(), groups)
    values[state_name("hub.bore_diameter")] = "6"
    assert model.from_dict(design_from_state(values, groups)).hub.bore_diameter == 6.0

    server = get_server("studio_panel_test", client_type="vue3")
    with SinglePageLayout(server) as layout, layout.content:
        parameter_panel(groups)
    page = layout.html
    assert 'id="field-hub-bore-diameter"' in page and 'max="500.0"' in page


def test_state_round_trip_gives_the_same_design(groups):
    design = PropellerParameters().with_values(
        {
            "blades": 5,
            "hub.radius": 12.5,
            "centerline.p2": [20.0, 4.0, 24.0],
            "airfoil.camber_normal": False,
            "centerline.frame": "rotation_minimizing",
            "export.formats": ["step", "3mf"],
            "handedness": "ccw",
        }
    )
    values = state_values(design.to_dict(), groups)
    assert values[state_name("blades")] == 5
    assert values[state_name("centerline.p2", 1)] == 4.0
    assert PropellerParameters.from_dict(design_from_state(values, groups)) == design


def test_typed_text_becomes_numbers_and_whole_numbers_stay_whole(groups):
    values = state_values(PropellerParameters().to_dict(), groups)
    values[state_name("blades")] = "4"
    values[state_name("hub.radius")] = "12"
    values[state_name("centerline.p4", 0)] = " 90.5 "
    design = PropellerParameters.from_dict(design_from_state(values, groups))
    assert (design.blades, design.hub.radius, design.centerline.p4[0]) == (4, 12.0, 90.5)
    assert isinstance(design.hub.radius, float)


@pytest.mark.parametrize(
    ("key", "text", "expected"),
    [
        ("hub.radius", "abc", "hub.radius must be a number, got 'abc'"),
        ("hub.radius", "", "hub.radius needs a value"),
        ("centerline.p3", "1e", "centerline.p3[2] must be a number, got '1e'"),
    ],
)
def test_text_that_is_not_a_number_is_refused_naming_the_field(groups, key, text, expected):
    values = state_values(PropellerParameters().to_dict(), groups)
    field = next(f for group in groups for f in group.fields if f.key == key)
    values[field.state_names[-1]] = text
    with pytest.raises(ParameterError) as refusal:
        design_from_state(values, groups)
    assert str(refusal.value) == expected


def test_a_fraction_of_a_blade_is_refused_by_the_schema_itself(groups):
    values = state_values(PropellerParameters().to_dict(), groups)
    values[state_name("blades")] = "3.5"
    with pytest.raises(ParameterError, match="blades"):
        PropellerParameters.from_dict(design_from_state(values, groups))


def test_refusals_are_placed_at_the_field_they_name(groups):
    assert field_of_message("hub.radius = 0.1 is out of range; allowed [0.5, 1000]", groups) == (
        "hub.radius",
        None,
    )
    assert field_of_message("centerline.p4[1] = 18 is out of range; allowed (-1, 9)", groups) == (
        "centerline.p4",
        1,
    )
    assert field_of_message("transforms.scale_x must stay positive on s in [0, 1]", groups) == (
        "transforms.scale_x",
        None,
    )
    assert (
        field_of_message("the blade's root (s = 0) section leaves the hub's inset", groups) is None
    )


def test_integer_fields_with_a_range_get_a_slider(groups):
    blades = next(f for group in groups for f in group.fields if f.key == "blades")
    assert blades.kind is FieldKind.INTEGER
    assert blades.slider is not None and blades.slider[2] == 1.0


# -- preview
# -----------------------------------------------------------------------------------------


def test_hub_cylinder_mesh_is_closed_with_the_hub_volume():
    mesh = cylinder_mesh(10.0, 20.0, segments=256)
    assert _closed(mesh)
    volume = TriangleMesh(mesh.vertices, mesh.triangles).volume
    assert volume == pytest.approx(np.pi * 10.0**2 * 20.0, rel=1e-3)


def test_preview_draws_every_blade_closed_and_rotated_about_the_axis():
    params = PropellerParameters().with_values({"blades": 4, "phase_deg": 10.0})
    scene = preview_scene(params)
    assert [part.part for part in scene.parts] == [HUB_PART, 0, 1, 2, 3]
    assert all(_closed(part) for part in scene.parts)
    blade_0, blade_1 = scene.parts[1].vertices, scene.parts[2].vertices
    quarter_turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(blade_1, blade_0 @ quarter_turn.T, atol=1e-9)
    assert len(scene.sections) == 4 and scene.sections[0].shape == (25, 80, 3)


def test_preview_of_the_mirror_image_is_the_mirrored_preview():
    clockwise = preview_scene(PropellerParameters().with_values({"phase_deg": 20.0}))
    counter = preview_scene(
        PropellerParameters().with_values({"phase_deg": 20.0, "handedness": "ccw"})
    )
    for cw_part, ccw_part in zip(clockwise.parts[1:], counter.parts[1:]):
        cw_mesh = TriangleMesh(cw_part.vertices, cw_part.triangles)
        ccw_mesh = TriangleMesh(ccw_part.vertices, ccw_part.triangles)
        assert ccw_mesh.is_watertight() and ccw_mesh.volume == pytest.approx(
            cw_mesh.volume, rel=1e-12
        )
    # Some blade of the mirror image is the mirror of blade 0 (which one depends on the angles).
    mirrored_blade_0 = clockwise.parts[1].vertices * np.array([1.0, -1.0, 1.0])
    assert min(np.abs(part.vertices - mirrored_blade_0).max() for part in counter.parts[1:]) < 1e-9


def test_preview_applies_the_diameter_target():
    scene = preview_scene(PropellerParameters().with_values({"diameter": 60.0}))
    assert scene.tip_diameter_mm == pytest.approx(60.0, rel=5e-3)


def test_preview_refuses_what_the_build_refuses():
    with pytest.raises(GeometryError, match="hub's inset"):
        preview_scene(PropellerParameters().with_values({"hub.radius": 3.0}))


# -- exact build
# ------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def light_propeller(light_params):
    from torus_cad.propeller import build_propeller

    return build_propeller(light_params.with_values({"blades": 4}))


def test_exact_tessellation_splits_the_solid_into_hub_and_blades(light_propeller):
    from torus_cad.studio.exact import tessellate_parts

    parts = tessellate_parts(light_propeller)
    assert [part.part for part in parts] == [HUB_PART, 0, 1, 2, 3]
    vertices = np.concatenate([part.vertices for part in parts])
    offsets = np.cumsum([0] + [len(part.vertices) for part in parts[:-1]])
    triangles = np.concatenate([part.triangles + offset for part, offset in zip(parts, offsets)])
    # faces are outward, so the parts enclose the solid
    volume = TriangleMesh(vertices, triangles).volume
    assert volume == pytest.approx(light_propeller.mass_properties().volume_mm3, rel=0.01)
    # Each blade sits a quarter turn from the one before: compare the blades' centres' angles.
    angles = [np.degrees(np.arctan2(*part.vertices.mean(axis=0)[1::-1])) for part in parts[1:]]
    steps = np.mod(np.diff(angles), 360.0)
    np.testing.assert_allclose(steps, 90.0, atol=1.0)


def test_tip_diameter_reaches_the_exact_solids_outermost_point(light_params, light_propeller):
    from torus_cad.studio.exact import tessellate_parts
    from torus_cad.studio.scene import tip_diameter_mm

    exact_vertices = np.concatenate([part.vertices for part in tessellate_parts(light_propeller)])
    # vertices lie on the solid
    reach = 2.0 * np.hypot(exact_vertices[:, 0], exact_vertices[:, 1]).max()
    tip = tip_diameter_mm(light_params.with_values({"blades": 4}))
    # the display mesh's chords may cut inside by < 0.1 mm
    assert reach - 1e-3 <= tip <= reach + 0.1
    preview = preview_scene(light_params.with_values({"blades": 4}))
    assert tip * (1 - 5e-3) <= preview.tip_diameter_mm <= tip


# -- the worker process
# ------------------------------------------------------------------------------


def _collect(requests, tmp_path, kill_after_start=False, timeout_s=240.0, **limits):
    """Run requests through a BuildRunner (each superseding the one before); the messages received.
    ``limits``: the runner's time_limit_s and memory_limit_bytes."""
    from torus_cad.studio.messages import BuildRequest
    from torus_cad.studio.worker import BuildRunner

    messages: list[tuple[str, int, object]] = []

    async def run() -> None:
        done = asyncio.Event()

        def on_message(kind, build_id, payload):
            messages.append((kind, build_id, payload))
            if build_id == len(requests) and kind in ("files", "refused", "failed"):
                done.set()

        runner = BuildRunner(on_message, **limits)
        for build_id, design in enumerate(requests, start=1):
            runner.submit(BuildRequest(build_id, design, tmp_path / str(build_id)))
        if kill_after_start:
            await asyncio.sleep(0.5)
            os.kill(runner._process.pid, signal.SIGKILL)
        await asyncio.wait_for(done.wait(), timeout_s)
        runner.cancel()

    asyncio.run(run())
    return messages


def test_a_newer_build_supersedes_the_older_one(light_params, tmp_path):
    from torus_cad.kernel.step_readback import read_step

    older = light_params.with_values({"blades": 3}).to_dict()
    newer = light_params.with_values({"blades": 5}).to_dict()
    messages = _collect([older, newer], tmp_path)
    assert {build_id for _, build_id, _ in messages} == {2}
    assert [kind for kind, _, _ in messages] == ["solid", "properties", "files"]
    solid = messages[0][2]
    assert [part.part for part in solid.parts] == [HUB_PART, 0, 1, 2, 3, 4]
    step = messages[2][2]["paths"]["step"]
    assert step.parent == tmp_path / "2" and len(read_step(step).Solids()) == 1


def test_a_refused_design_and_a_crashed_build_are_reported_not_raised(light_params, tmp_path):
    refused = light_params.to_dict()
    refused["hub"]["radius"] = 3.0  # valid field, but the blade's root leaves the hub
    messages = _collect([refused], tmp_path)
    assert [(kind, build_id) for kind, build_id, _ in messages] == [("refused", 1)]
    assert "hub's inset" in messages[0][2]

    heavy = light_params.with_values(
        {"resolution.sections": 200, "resolution.points": 400}
    ).to_dict()
    messages = _collect([heavy], tmp_path / "crash", kill_after_start=True)
    assert messages[-1][0] == "failed" and "stopped unexpectedly" in messages[-1][2]


def test_a_build_over_its_time_limit_is_stopped_and_reported(light_params, tmp_path):
    heavy = light_params.with_values(
        {"resolution.sections": 200, "resolution.points": 400}
    ).to_dict()
    messages = _collect([heavy], tmp_path, time_limit_s=1.0)
    assert [kind for kind, _, _ in messages] == ["failed"], messages
    assert "the exact build took longer than 1 s, the limit in the studio" in messages[0][2]


def test_a_build_over_its_memory_limit_fails_in_its_process_not_the_server(light_params, tmp_path):
    messages = _collect([light_params.to_dict()], tmp_path, memory_limit_bytes=64 << 20)
    assert [kind for kind, _, _ in messages] == ["failed"], messages
    assert "ran out of memory" in messages[0][2] or "stopped unexpectedly" in messages[0][2]


# -- the vortex solver's numbers
# ---------------------------------------------------------------------


def _performance_state():
    """A trame state holding the performance card's keys (no server started, no page)."""
    from trame.app import get_server

    from torus_cad.studio.performance_card import state_defaults

    state = get_server("studio_performance_test", client_type="vue3").state
    state.update(state_defaults())
    return state


async def _numbers_shown(state, performance, timeout_s=600.0):
    """Wait until the latest solve's numbers (or failure) are shown; the thrust readout, N."""
    from torus_cad.studio.performance_card import COMPUTING

    deadline = asyncio.get_running_loop().time() + timeout_s
    while performance.running or state.perf_thrust_text == COMPUTING:
        assert asyncio.get_running_loop().time() < deadline, "the vortex solve did not finish"
        await asyncio.sleep(0.1)
    assert not state.perf_failure, state.perf_failure
    return float(state.perf_thrust_text.removesuffix(" N"))


def test_a_higher_rpm_raises_the_thrust_shown_and_a_bad_rpm_keeps_the_last_numbers(tmp_path):
    from torus_cad.studio.performance_card import COMPUTING, Performance

    state = _performance_state()

    async def run() -> None:
        performance = Performance(state, tmp_path)
        performance.set_design(PropellerParameters())
        assert state.perf_thrust_text == COMPUTING
        thrust_10k = await _numbers_shown(state, performance)
        assert (
            state.perf_merit_label == "figure of merit" and 0.0 < float(state.perf_merit_text) < 1.0
        )
        assert state.perf_point_text.startswith("at 10000 rpm, 0 m/s")
        assert state.perf_power_text.endswith(" W") and state.perf_plot.startswith(
            "data:image/png;base64,"
        )
        for rpm in ("11000", "12000"):  # typed in a row: the 11000 rpm solve is killed, never shown
            state.perf_rpm = rpm
            performance.on_operating_point()
        thrust_12k = await _numbers_shown(state, performance)
        assert state.perf_point_text.startswith("at 12000 rpm, 0 m/s")
        assert thrust_12k > 1.2 * thrust_10k  # thrust ~ rpm^2: (12/10)^2 = 1.44
        shown = {name: state[name] for name in ("perf_thrust_text", "perf_power_text", "perf_plot")}
        state.perf_rpm = "99999"
        performance.on_operating_point()
        assert state.perf_rpm_error.startswith("rpm = 99999 is out of range; allowed [0, ")
        assert "helical tip Mach" in state.perf_rpm_error and not state.perf_airspeed_error
        assert not performance.running
        assert {name: state[name] for name in shown} == shown  # the last numbers stay
        state.perf_rpm, state.perf_airspeed = "12000", "-1"
        performance.on_operating_point()
        assert state.perf_airspeed_error.startswith(
            "airspeed = -1 m/s is out of range; allowed [0, 100] m/s"
        )
        assert not state.perf_rpm_error and not performance.running
        performance.cancel()

    asyncio.run(run())


def test_a_solve_that_does_not_converge_shows_its_one_line_instead_of_numbers(
    tmp_path, monkeypatch
):
    import multiprocessing

    from torus_cad.errors import KernelError
    from torus_cad.studio import vortex_run
    from torus_cad.studio.performance_card import NO_NUMBER, Performance, PerformanceRequest

    reason = (
        "the vortex solve did not converge: the thrust "
        "still changed by 3.5 % a sweep after 30 sweeps"
    )

    def diverging(*_, **__):
        raise KernelError(reason)

    monkeypatch.setattr(vortex_run, "vortex_performance", diverging)
    receiver, sender = multiprocessing.Pipe(duplex=False)
    vortex_run.run_vortex(
        PerformanceRequest(7, PropellerParameters().to_dict(), 10000.0, 0.0, tmp_path), sender
    )
    assert receiver.recv() == ("failed", 7, reason)

    state = _performance_state()

    async def run() -> None:
        performance = Performance(state, tmp_path)
        performance._request_id, performance._solving = 7, (10000.0, 0.0)
        performance._on_message("failed", 6, "an older request's")  # superseded: dropped
        assert not state.perf_failure
        performance._on_message("failed", 7, reason)
        assert state.perf_failure == f"{reason} (at 10000 rpm, 0 m/s)"
        assert state.perf_thrust_text == state.perf_power_text == state.perf_merit_text == NO_NUMBER

    asyncio.run(run())


def test_an_upload_holds_one_design_and_plainly_named_files():
    from torus_cad.studio.uploads import MAX_UPLOAD_BYTES, upload_files

    design = {"name": "d.toml", "content": b"blades = 3\n"}
    assert upload_files([design, {"name": "foil.dat", "content": b"x"}]) == {
        "d.toml": b"blades = 3\n",
        "foil.dat": b"x",
    }
    for uploads, reason in [
        ([{"name": "foil.dat", "content": b"x"}], "holds 0 .toml files"),
        ([design, {"name": "e.toml", "content": b""}], "holds 2 .toml files"),
        ([design, {"name": ".hidden", "content": b""}], "name must be letters"),
        ([design, {"name": "d.toml", "content": b""}], "each name once"),
        (
            [{"name": "d.toml", "content": b" " * (MAX_UPLOAD_BYTES + 1)}],
            f"at most {MAX_UPLOAD_BYTES:,} bytes",
        ),
        ([{"name": "d.toml", "content": "text"}], "could not be read"),
    ]:
        with pytest.raises(ParameterError, match=reason):
            upload_files(uploads)
    # base names only
    assert list(upload_files([{"name": "../../etc/d.toml", "content": b""}])) == ["d.toml"]


# -- command line
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("arguments", "expected"),
    [
        (["--port", "70000"], "--port = 70000 is out of range"),
        (["--set", "hub.radius=0.1"], "hub.radius = 0.1 is out of range"),
        (["--host", ""], "--host must name an address to listen on"),
        (["--host", "  "], "--host must name an address to listen on"),
        (["--files", "/nonexistent-folder"], "--files '/nonexistent-folder' is not a folder"),
    ],
)
def test_studio_refuses_bad_input_before_serving(arguments, expected):
    result = subprocess.run(
        [sys.executable, "-m", "torus_cad", "studio", *arguments],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 2
    assert expected in result.stderr and result.stdout == ""


def test_start_message_says_who_can_connect():
    from torus_cad.studio.server import start_message

    assert "only this machine can connect" in start_message("127.0.0.1", 8080)
    assert "http://127.0.0.1:8080/" in start_message("127.0.0.1", 8080)
    assert "other machines" in start_message("0.0.0.0", 8080)


def test_a_busy_port_is_reported_as_such():
    import socket

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        result = subprocess.run(
            [sys.executable, "-m", "torus_cad", "studio", "--port", str(port)],
            capture_output=True,
            text=True,
            timeout=300,
            check=False,
        )
    assert result.returncode == 1
    assert result.stderr.strip() == (
        f"torus-cad: studio: port {port} on 127.0.0.1 is already in use (another studio "
        "or server?); choose another with --port, or --port 0 for any free one"
    )


@pytest.mark.parametrize(
    ("signum", "code"), [(signal.SIGINT, 130), (signal.SIGTERM, 143)], ids=["SIGINT", "SIGTERM"]
)
def test_a_signal_stops_the_studio_with_its_exit_code_and_one_line(signum, code):
    from studio_driver import StudioProcess

    with StudioProcess() as studio:
        process = studio._process
        assert process is not None
        process.send_signal(signum)
        assert process.wait(timeout=60) == code
    assert (
        studio.output[-1].strip().splitlines()[-1]
        == f"torus-cad: studio stopped by {signal.Signals(signum).name}"
    )
