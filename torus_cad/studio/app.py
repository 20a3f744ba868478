"""The studio page's server-side logic (trame, Vuetify 3, a VTK view drawn in the browser).

A change in the panel goes through the same validation as ``torus-cad build``; a valid design
is drawn at once from the kernel-free preview (torus_cad.studio.scene) and its exact solid is
built in a worker process (torus_cad.studio.worker), which replaces the preview when it is
ready. A refused design leaves the last good propeller on screen and puts the one-line reason
next to the field that was changed.

The studio is a service on a network: an uploaded design is read off the event loop, as
``torus-cad build FILE`` reads it, and may name only files uploaded with it or in ``--files``
(torus_cad.studio.uploads); the server's start and stop are torus_cad.studio.server's.

Once a design's exact solid is built, the vortex solver's numbers at the rpm and airspeed entered
are solved in a process of their own (torus_cad.studio.performance_card); a newer design or point
supersedes them.
"""

from __future__ import annotations

import asyncio
import logging
import shutil
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from torus_cad.build_stages import Stage
from torus_cad.errors import GeometryError, ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.studio.messages import BuildRequest, SolidResult
from torus_cad.studio.panel import (
    PanelField,
    PanelGroup,
    design_from_state,
    field_of_message,
    schema_groups,
    state_values,
)
from torus_cad.studio.performance_card import Performance, state_defaults
from torus_cad.studio.scene import PreviewScene, preview_scene
from torus_cad.studio.uploads import is_design, read_upload
from torus_cad.studio.worker import BuildRunner

LOG = logging.getLogger(__name__)

#: Default density for the mass readout: PLA (g/cm^3), as ``torus-cad build``.
DEFAULT_DENSITY_G_CM3 = 1.24

#: Allowed density, g/cm^3 (as ``torus-cad build --density``).
DENSITY_RANGE_G_CM3 = (0.0, 25.0)

#: The download buttons' names of the files a build writes (keys of Propeller.write's paths).
DOWNLOAD_LABELS = {
    "step": "STEP",
    "stl": "STL",
    "3mf": "3MF",
    "sections_csv": "sections CSV",
    "sections_png": "sections PNG",
    "json": "report JSON",
}


@dataclass
class _Exact:
    """The exact build on screen (or being built)."""

    build_id: int
    design: PropellerParameters
    started: float
    properties: dict[str, Any] | None = None
    files: dict[str, Path] = field(default_factory=dict)
    changed: set[str] = field(default_factory=set)  # the keys edited into this design


class Studio:
    """State, callbacks and layout of one studio page, bound to a trame server."""

    def __init__(
        self,
        server: Any,
        design: PropellerParameters,
        workdir: Path,
        files_folder: Path | None = None,
    ) -> None:
        from torus_cad.studio.view import PropellerView

        self.server, self.state, self.ctrl = server, server.state, server.controller
        self.workdir = workdir
        self.files_folder = files_folder.resolve() if files_folder is not None else None
        self._uploads = 0
        self.groups: list[PanelGroup] = schema_groups()
        self.fields: dict[str, PanelField] = {
            f.key: f for group in self.groups for f in group.fields
        }
        self.view = PropellerView()
        self.design = design  # the last good design (on screen once the first preview is drawn)
        self._displayed: PropellerParameters | None = None  # the design drawn in the view
        self.exact: _Exact | None = None  # the newest exact build of a good design
        self._shown_exact: _Exact | None = None  # the exact build whose files the downloads give
        self._runner = BuildRunner(self._on_build_message)
        self.performance = Performance(self.state, workdir)
        self._previewer = ThreadPoolExecutor(max_workers=1, thread_name_prefix="torus-cad-preview")
        self._changed: set[str] = set()  # keys edited since the last good design
        self._last_changes: set[str] = set()  # the keys edited into the last good design
        self._dirty = False
        self._refresh_task: asyncio.Task[None] | None = None
        self._build_counter = 0
        self._change_time = time.perf_counter()
        self._trusted_paths = {
            name: value
            for name, value in state_values(design.to_dict(), self.groups).items()
            if any(name in f.state_names for f in self.fields.values() if f.read_only)
        }
        # the newest exact solid shown
        self._last_good: tuple[PropellerParameters, SolidResult] | None = None
        self._init_state()
        self._bind()

    # -- state ----------------------------------------------------------------------------------
    def _init_state(self) -> None:
        self.state.update(
            {
                **state_values(self.design.to_dict(), self.groups),
                "field_errors": {},
                "element_errors": {},
                "refusal": "",
                "status": "starting",
                "building": False,
                "downloads": [],
                "show_sections": False,
                "density_g_cm3": DEFAULT_DENSITY_G_CM3,
                "density_error": "",
                "upload_file": None,
                "upload_message": "",
                "upload_error": "",
                "file_stem": self.design.name,
                "volume_text": "…",
                "mass_text": "…",
                "area_text": "…",
                "tip_text": "…",
                "valid_text": "…",
                "route_text": "",
                "stage_rows": [],
                "preview_ms": 0.0,
                "exact_ms": 0.0,
                "preview_stamp": 0,
                "preview_detail": "",
                "exact_stamp": 0,
                "failure": "",
                **state_defaults(),
            }
        )

    def _bind(self) -> None:
        for panel_field in self.fields.values():
            for name in panel_field.state_names:
                self.state.change(name)(self._change_handler(panel_field.key))
        self.state.change("show_sections")(self._on_sections_toggle)
        self.state.change("density_g_cm3")(self._on_density)
        self.state.change("perf_rpm", "perf_airspeed")(self.performance.on_operating_point)
        self.state.change("upload_file")(self._on_upload)
        self.ctrl.trigger("download_file")(self._download)
        self.ctrl.trigger("download_toml")(self._download_toml)
        self.ctrl.on_server_ready.add(self._on_ready)
        self.ctrl.on_server_exited.add(self.shut_down)

    def _change_handler(self, key: str) -> Any:
        def changed(**_: Any) -> None:
            self._changed.add(key)
            self._schedule_refresh()

        return changed

    def _schedule_refresh(self) -> None:
        self._dirty = True
        self._change_time = time.perf_counter()
        if self._refresh_task is None or self._refresh_task.done():
            self._refresh_task = asyncio.get_event_loop().create_task(self._refresh())
            self._refresh_task.add_done_callback(_log_failure)

    def _on_ready(self, **_: Any) -> None:
        self._schedule_refresh()

    def shut_down(self, **_: Any) -> None:
        """Stop the studio's work: cancel the build in progress and the previews not yet started.

        Called when the server exits, and by :func:`torus_cad.studio.server.serve` on its way out; a
        second call does nothing more.

        Args:
            **_: what the server's exit event passes; not used.
        """
        self._runner.cancel()
        self.performance.cancel()
        self._previewer.shutdown(wait=False, cancel_futures=True)

    # -- a change: validate, preview, build --------------------------------------------------------
    def _values(self) -> dict[str, Any]:
        """The panel's values; file paths always the trusted design's, whatever the page sends."""
        values = {
            name: self.state[name]
            for panel_field in self.fields.values()
            for name in panel_field.state_names
        }
        return {**values, **self._trusted_paths}

    async def _refresh(self) -> None:
        loop = asyncio.get_running_loop()
        while self._dirty:
            self._dirty = False
            started = self._change_time
            times = {"wait": time.perf_counter() - started}
            try:
                params = PropellerParameters.from_dict(
                    design_from_state(self._values(), self.groups)
                )
                if params == self._displayed and not self.state.refusal:
                    continue
                times["validate"] = time.perf_counter() - started - sum(times.values())
                scene = await loop.run_in_executor(self._previewer, preview_scene, params)
                times["surface + checks"] = time.perf_counter() - started - sum(times.values())
            except (ParameterError, GeometryError) as error:
                if not self._dirty:  # a newer change would replace the verdict anyway
                    self._refuse(str(error))
                continue
            except Exception as error:
                LOG.exception("preview failed")
                self._refuse(f"internal error ({type(error).__name__}): {error}")
                continue
            self._show_preview(params, scene, started, times)
            if not self._dirty:
                self._start_build(params, started)

    def _refuse(self, message: str) -> None:
        target = field_of_message(message, self.groups)
        # The reason goes next to the fields just changed and the field it names, if another.
        keys = sorted(self._changed | ({target[0]} if target is not None else set())) or ["name"]
        element_errors = (
            {f"{target[0]}[{target[1]}]": True}
            if target is not None and target[1] is not None
            else {}
        )
        with self.state:
            self.state.field_errors = {key: message for key in keys}
            sections = [key.rpartition(".")[0] or "propeller" for key in keys if key in self.fields]
            # show them
            self.state.open_groups = list(
                dict.fromkeys([*(self.state.open_groups or []), *sections])
            )
            self.state.element_errors = element_errors
            self.state.refusal = message
            self.state.status = "refused"

    def _show_preview(
        self,
        params: PropellerParameters,
        scene: PreviewScene,
        started: float,
        times: dict[str, float],
    ) -> None:
        self.design = self._displayed = params
        self._last_changes, self._changed = self._changed, set()
        self.view.show_parts(scene.parts, params.blades)
        self.view.show_sections(scene.sections, params.blades)
        self.view.set_sections_visible(self.state.show_sections)
        times["meshes"] = time.perf_counter() - started - sum(times.values())
        with self.state:
            self.state.field_errors, self.state.element_errors = {}, {}
            self.state.refusal, self.state.failure = "", ""
            self.state.status = "preview"
            self.state.file_stem = params.name
            # sampled at the design's resolution
            self.state.tip_text = f"≈ {scene.tip_diameter_mm:.2f} mm"
            self.ctrl.view_update()
            times["view update"] = time.perf_counter() - started - sum(times.values())
            self.state.preview_ms = round((time.perf_counter() - started) * 1000.0, 1)
            self.state.preview_detail = ", ".join(
                f"{name} {seconds * 1000.0:.0f}" for name, seconds in times.items()
            )
            self.state.preview_stamp += 1

    def _start_build(self, params: PropellerParameters, started: float) -> None:
        self._build_counter += 1
        build_id = self._build_counter
        self.exact = _Exact(build_id, params, started, changed=set(self._last_changes))
        self._runner.submit(
            BuildRequest(build_id, params.to_dict(), self.workdir / "builds" / str(build_id))
        )
        self.performance.hold()  # solved once the build is done: the build keeps the CPU
        with self.state:
            self.state.building = True
            for name in ("volume_text", "mass_text", "area_text", "valid_text"):
                self.state[name] = "…"
            self.state.route_text = ""
            self.state.downloads = []

    # -- results of the exact build ----------------------------------------------------------------
    def _on_build_message(self, kind: str, build_id: int, payload: Any) -> None:
        exact = self.exact
        if exact is None or build_id != exact.build_id:
            return  # a superseded build
        try:
            with self.state:
                getattr(self, f"_on_{kind}")(exact, payload)
        except Exception:
            LOG.exception("handling the build's %s message failed", kind)

    def _on_solid(self, exact: _Exact, solid: SolidResult) -> None:
        self._last_good = (exact.design, solid)
        self.view.show_parts(solid.parts, exact.design.blades)
        self.ctrl.view_update()
        if not self.state.refusal:  # a refused newer value stays the news
            self.state.status = "exact"
        self.state.valid_text = "valid: 1 closed solid"  # the build fails on anything else
        self.state.route_text = solid.fuse_route
        self.state.stage_rows = [
            {"stage": _stage_label(name), "ms": f"{seconds * 1000.0:.0f}"}
            for name, seconds in solid.stage_seconds.items()
            if name != Stage.PARAMETERS
        ]
        self.state.exact_ms = round((time.perf_counter() - exact.started) * 1000.0, 1)
        self.state.exact_stamp += 1

    def _on_properties(self, exact: _Exact, properties: dict[str, Any]) -> None:
        exact.properties = properties
        self.state.volume_text = f"{properties['volume_mm3']:.2f} mm³"
        self.state.area_text = f"{properties['surface_area_mm2']:.2f} mm²"
        self.state.tip_text = f"{properties['tip_diameter_mm']:.3f} mm"
        self.state.stage_rows = [
            *self.state.stage_rows,
            {"stage": "mass properties", "ms": f"{properties['seconds'] * 1000.0:.0f}"},
        ]
        self._update_mass()

    def _on_files(self, exact: _Exact, files: dict[str, Any]) -> None:
        exact.files = dict(files["paths"])
        previous, self._shown_exact = self._shown_exact, exact
        if previous is not None and previous.files:
            shutil.rmtree(next(iter(previous.files.values())).parent, ignore_errors=True)
        self.state.stage_rows = [
            *self.state.stage_rows,
            {"stage": "files (as torus-cad build)", "ms": f"{files['seconds'] * 1000.0:.0f}"},
        ]
        self.state.building = False
        self.state.downloads = [
            {"kind": kind, "label": DOWNLOAD_LABELS.get(kind, kind), "file": path.name}
            for kind, path in exact.files.items()
        ]
        self.performance.set_design(exact.design)

    def _on_refused(self, exact: _Exact, message: str) -> None:
        """A check only the build makes (e.g. the hub's mounting features) refused the design: as a
        refusal of the preview, with the last exact propeller back on screen."""
        self.state.building = False
        self._changed.update(exact.changed)
        self._refuse(message)
        if self._last_good is not None:
            design, solid = self._last_good
            self.design = design
            self._displayed = None  # the view no longer shows the refused design's preview
            self.view.show_parts(solid.parts, design.blades)
            self.ctrl.view_update()
            self.performance.set_design(design)  # the numbers of the propeller back on screen

    def _on_failed(self, exact: _Exact, message: str) -> None:
        self.state.building = False
        self.state.status = "failed"
        self.state.failure = message
        self.performance.set_design(exact.design)  # the design passed every check before the kernel

    # -- readouts, toggles, files -----------------------------------------------------------------
    def _update_mass(self) -> None:
        properties = self.exact.properties if self.exact is not None else None
        if properties is None or self.state.density_error:
            self.state.mass_text = "…"
            return
        mass_g = properties["volume_mm3"] * float(self.state.density_g_cm3) * 1e-3
        self.state.mass_text = f"{mass_g:.3f} g"

    def _on_density(self, density_g_cm3: Any, **_: Any) -> None:
        low, high = DENSITY_RANGE_G_CM3
        try:
            value = float(density_g_cm3)
        except (TypeError, ValueError):
            self.state.density_error = f"density must be a number in g/cm^3, got {density_g_cm3!r}"
        else:
            ok = low < value <= high
            self.state.density_error = (
                ""
                if ok
                else f"density = {value:g} is out of range; allowed ({low:g}, {high:g}] g/cm^3"
            )
        self._update_mass()

    def reset_view(self) -> None:
        """Back to the default viewpoint, framing the whole propeller."""
        self.view.reset_camera()
        self.ctrl.view_push_camera()

    def _on_sections_toggle(self, show_sections: bool, **_: Any) -> None:
        self.view.set_sections_visible(show_sections)
        self.ctrl.view_update()

    def _download(self, kind: str) -> Any:
        """The bytes of one file of the exact solid on screen; ``kind`` picks among the files the
        server made (never a path)."""
        exact = self._shown_exact
        if exact is None or kind not in exact.files:
            return None
        return self.server.protocol.addAttachment(exact.files[kind].read_bytes())

    def _download_toml(self) -> Any:
        text = (
            "# torus_cad design, saved by torus-cad studio; "
            "build it with: torus-cad build <this file>\n"
        )
        return self.server.protocol.addAttachment((text + self.design.to_toml()).encode())

    def _on_upload(self, upload_file: Any, **_: Any) -> None:
        if not upload_file:
            return
        uploads = upload_file if isinstance(upload_file, list) else [upload_file]
        self.state.upload_file = None
        self.state.upload_message, self.state.upload_error = "reading the upload…", ""
        task = asyncio.get_event_loop().create_task(self._open_upload(uploads))
        task.add_done_callback(_log_failure)

    async def _open_upload(self, uploads: Sequence[Any]) -> None:
        """Read the upload in the preview's thread: the event loop keeps serving every other
        client."""
        loop = asyncio.get_running_loop()
        try:
            params = await loop.run_in_executor(self._previewer, self._read_upload, uploads)
        except ParameterError as error:
            with self.state:
                self.state.upload_error, self.state.upload_message = str(error), ""
            return
        design_name = next(str(upload.get("name", "")) for upload in uploads if is_design(upload))
        with self.state:
            self.state.upload_error = ""
            self.state.upload_message = f"opened {design_name[:80]}"
            values = state_values(params.to_dict(), self.groups)
            self._trusted_paths = {name: values[name] for name in self._trusted_paths}
            self.state.update(values)

    def _read_upload(self, uploads: Sequence[Any]) -> PropellerParameters:
        """The design of an upload, in a new folder of the studio's
        (:func:`torus_cad.studio.uploads.read_upload`)."""
        self._uploads += 1
        read_only = [
            panel_field.key for panel_field in self.fields.values() if panel_field.read_only
        ]
        return read_upload(
            uploads, self.workdir / "uploads" / str(self._uploads), read_only, self.files_folder
        )


def _stage_label(name: str) -> str:
    """Words for a stage of the build (torus_cad.build_stages), or the name of the studio's own
    step."""
    return Stage(name).label if name in Stage.__members__.values() else name.replace("_", " ")


def _log_failure(task: asyncio.Task[None]) -> None:
    if not task.cancelled() and task.exception() is not None:
        LOG.error("studio update failed", exc_info=task.exception())
