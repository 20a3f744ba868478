"""The studio page's layout (Vuetify 3 widgets): panel on the left, the 3D view, readouts and
downloads.

The parameter fields are generated from the panel's groups (torus_cad.studio.panel), so every
parameter of the schema gets a field without being listed here.
"""

from __future__ import annotations

from typing import Any, Protocol

from trame.ui.vuetify3 import SinglePageWithDrawerLayout
from trame.widgets import html
from trame.widgets import vtk as vtk_widgets
from trame.widgets import vuetify3 as v3

from torus_cad.studio.panel import FieldKind, PanelField, PanelGroup
from torus_cad.studio.performance_card import SOLVER_LABEL


class Studio(Protocol):
    """What the layout binds to (torus_cad.studio.app.Studio): the trame server and its controller,
    the panel's groups, the VTK view whose window is shown, and the view reset of the toolbar."""

    server: Any
    ctrl: Any
    groups: list[PanelGroup]
    view: Any

    def reset_view(self) -> None: ...


#: Width of the parameters drawer, pixels.
DRAWER_WIDTH = 400

_CSS = """
.studio-field .v-field__input { font-variant-numeric: tabular-nums; }
.studio-refusal { white-space: normal; }
.studio-readouts td { padding: 2px 8px !important; height: auto !important; }
"""


#: The status chip's colour: red for a refusal or failure, green once the exact solid is shown.
_STATUS_COLOR = (
    "['refused', 'failed'].includes(status) ? 'error' "
    ": (status === 'exact' ? 'success' : 'primary')"
)


def _js_key(text: str) -> str:
    return text.replace("\\", "\\\\").replace("'", "\\'")


def _js_list(items: tuple[str, ...]) -> str:
    """A JavaScript array literal of strings (trame reads a Python list as a state name and
    default)."""
    return "[" + ", ".join(f"'{_js_key(item)}'" for item in items) + "]"


def _error_of(panel_field: PanelField) -> str:
    return f"field_errors['{_js_key(panel_field.key)}'] || []"


def field_id(key: str) -> str:
    """The DOM id of a parameter's input, e.g. ``hub.radius`` -> ``field-hub-radius``."""
    return "field-" + key.replace(".", "-").replace("_", "-")


def _number_attributes(panel_field: PanelField) -> dict[str, object]:
    attributes: dict[str, object] = {"type": "number"}
    if panel_field.low is not None:
        attributes["min"] = panel_field.low
    if panel_field.high is not None:
        attributes["max"] = panel_field.high
    attributes["step"] = (
        panel_field.slider[2]
        if panel_field.slider
        else ("1" if panel_field.kind is FieldKind.INTEGER else "any")
    )
    return attributes


def _scalar_field(panel_field: PanelField) -> None:
    name = panel_field.state_names[0]
    common = {
        "label": panel_field.label,
        "hint": panel_field.hint,
        "persistent_hint": False,
        "error_messages": (_error_of(panel_field),),
        "density": "compact",
        "variant": "outlined",
        "classes": "studio-field",
        "id": field_id(panel_field.key),
        "hide_details": "auto",
    }
    if panel_field.kind is FieldKind.BOOLEAN:
        v3.VSwitch(
            v_model=(name,),
            color="primary",
            label=panel_field.label,
            hint=panel_field.hint,
            persistent_hint=True,
            error_messages=(_error_of(panel_field),),
            density="compact",
            id=field_id(panel_field.key),
            hide_details="auto",
        )
    elif panel_field.kind is FieldKind.CHOICE:
        v3.VSelect(v_model=(name,), items=(_js_list(panel_field.choices),), **common)
    elif panel_field.kind is FieldKind.CHOICES:
        v3.VSelect(
            v_model=(name,),
            items=(_js_list(panel_field.choices),),
            multiple=True,
            chips=True,
            **common,
        )
    elif panel_field.read_only:  # a file path: the server would read it, so the page may not set it
        v3.VTextField(
            v_model=(name,),
            **{
                **common,
                "hint": f"{panel_field.hint} (set in the design file the studio was started with)",
            },
            readonly=True,
        )
    elif panel_field.kind in (FieldKind.TEXT, FieldKind.NUMBERS):
        v3.VTextField(v_model=(name,), **common)
    else:
        v3.VTextField(
            v_model=(name,), suffix=panel_field.unit, **common, **_number_attributes(panel_field)
        )
        if panel_field.slider is not None:
            low, high, step = panel_field.slider
            v3.VSlider(
                v_model_number=(name,),
                min=low,
                max=high,
                step=step,
                density="compact",
                hide_details=True,
                color="primary",
                classes="mt-n2 mb-1 mx-2",
                id=field_id(panel_field.key) + "-slider",
            )


def _vector_field(panel_field: PanelField) -> None:
    key = _js_key(panel_field.key)
    html.Div(panel_field.label, classes="text-body-2 mt-1", title=panel_field.hint)
    with v3.VRow(dense=True, classes="mb-1"):
        for index, (name, unit) in enumerate(
            zip(panel_field.state_names, panel_field.element_units, strict=True)
        ):
            with v3.VCol():
                v3.VTextField(
                    v_model=(name,),
                    label=f"[{index}]",
                    suffix=unit,
                    density="compact",
                    variant="outlined",
                    hide_details=True,
                    classes="studio-field",
                    id=f"{field_id(panel_field.key)}-{index}",
                    error=(f"!!element_errors['{key}[{index}]']",),
                    title=panel_field.hint,
                    **_number_attributes(panel_field),
                )
    html.Div(
        f"{{{{ field_errors['{key}'] }}}}",
        v_if=(f"field_errors['{key}']",),
        classes="text-error text-caption studio-refusal",
        id=field_id(panel_field.key) + "-error",
    )
    html.Div(panel_field.hint, classes="text-caption text-medium-emphasis mb-2")


def _group(group: PanelGroup) -> None:
    with v3.VExpansionPanel(value=group.section or "propeller"):
        v3.VExpansionPanelTitle(group.title, classes="text-subtitle-1 font-weight-medium")
        with v3.VExpansionPanelText():
            if group.doc:
                html.Div(group.doc, classes="text-caption text-medium-emphasis mb-2")
            for panel_field in group.fields:
                with html.Div(classes="mb-2"):
                    (_vector_field if panel_field.is_vector else _scalar_field)(panel_field)


def parameter_panel(groups: list[PanelGroup], open_groups: int = 3) -> None:
    """One expansion panel per TOML table, a field per parameter; the first ``open_groups`` open."""
    with v3.VExpansionPanels(
        multiple=True,
        variant="accordion",
        v_model=("open_groups", [group.section or "propeller" for group in groups[:open_groups]]),
    ):
        for group in groups:
            _group(group)


def _readouts() -> None:
    with v3.VCard(classes="ma-2", elevation=2, id="readouts"):
        v3.VCardTitle("Readouts", classes="text-subtitle-1")
        with v3.VTable(density="compact", classes="studio-readouts"), html.Tbody():
            for label, variable, element_id in (
                ("volume", "volume_text", "readout-volume"),
                ("mass", "mass_text", "readout-mass"),
                ("area", "area_text", "readout-area"),
                ("tip diameter", "tip_text", "readout-tip"),
                ("validity", "valid_text", "readout-valid"),
            ):
                with html.Tr():
                    html.Td(label)
                    html.Td(f"{{{{ {variable} }}}}", id=element_id)
        v3.VTextField(
            v_model=("density_g_cm3",),
            label="density",
            suffix="g/cm³",
            type="number",
            step="0.01",
            min=0,
            max=25,
            density="compact",
            variant="outlined",
            classes="mx-3 mt-2",
            error_messages=("density_error || []",),
            hide_details="auto",
            id=field_id("density_g_cm3"),
        )
        html.Div(
            "{{ route_text }}", classes="text-caption text-medium-emphasis mx-3", id="readout-route"
        )
        v3.VCardSubtitle("stage times (exact build)", classes="mt-2")
        with (
            v3.VTable(density="compact", classes="studio-readouts"),
            html.Tbody(),
            html.Tr(v_for="row in stage_rows", key="row.stage"),
        ):
            html.Td("{{ row.stage }}")
            html.Td("{{ row.ms }} ms", classes="text-right text-no-wrap")
        html.Div(
            "preview {{ preview_ms }} ms after the change, exact solid {{ exact_ms }} ms",
            classes="text-caption text-medium-emphasis mx-3 mt-1",
            id="timings",
        )
        html.Div(
            "preview stages (ms): {{ preview_detail }}",
            classes="text-caption text-medium-emphasis mx-3",
            id="preview-detail",
        )
        html.Span("{{ preview_stamp }}", id="preview-stamp", style="display: none")
        html.Span("{{ exact_stamp }}", id="exact-stamp", style="display: none")
        v3.VCardSubtitle("download", classes="mt-2")
        with v3.VCardActions(classes="flex-wrap"):
            # One button per file the build wrote (export.formats, the blade-element table, the
            # report).
            v3.VBtn(
                "{{ item.label }}",
                v_for="item in downloads",
                key="item.kind",
                prepend_icon="mdi-download",
                variant="tonal",
                size="small",
                classes="ma-1",
                id=("'download-' + item.kind",),
                click="utils.download(item.file, trigger('download_file', [item.kind]))",
            )
            v3.VBtn(
                "design TOML",
                prepend_icon="mdi-download",
                variant="tonal",
                size="small",
                classes="ma-1",
                id="download-toml",
                click=(
                    "utils.download(file_stem + '.toml', "
                    "trigger('download_toml'), 'application/toml')"
                ),
            )


def _operating_point_field(name: str, label: str, unit: str) -> None:
    """An rpm or airspeed input of the performance card, its refusal under it (as the density's)."""
    v3.VTextField(
        v_model=(name,),
        label=label,
        suffix=unit,
        type="number",
        step="any",
        min=0,
        density="compact",
        variant="outlined",
        classes="mx-3 mt-2",
        error_messages=(f"{name}_error || []",),
        hide_details="auto",
        id=field_id(name),
    )


def _performance() -> None:
    """The vortex solver's numbers at the rpm and airspeed entered, and its loading plot
    (torus_cad.studio.performance_card)."""
    with v3.VCard(classes="ma-2", elevation=2, id="performance"):
        v3.VCardTitle("Performance (vortex solver)", classes="text-subtitle-1")
        _operating_point_field("perf_rpm", "rpm", "rpm")
        _operating_point_field("perf_airspeed", "airspeed", "m/s")
        with v3.VTable(density="compact", classes="studio-readouts mt-1"), html.Tbody():
            for label, variable, element_id in (
                ("thrust", "perf_thrust_text", "readout-thrust"),
                ("power", "perf_power_text", "readout-power"),
                ("{{ perf_merit_label }}", "perf_merit_text", "readout-merit"),
            ):
                with html.Tr():
                    html.Td(label)
                    html.Td(f"{{{{ {variable} }}}}", id=element_id)
        html.Div(
            "{{ perf_point_text }}",
            classes="text-caption text-medium-emphasis mx-3",
            id="readout-point",
        )
        html.Div(
            "{{ perf_failure }}",
            v_if=("perf_failure",),
            classes="text-caption text-error mx-3 studio-refusal",
            id="performance-failure",
        )
        html.Img(
            src=("perf_plot",),
            v_if=("perf_plot",),
            id="performance-plot",
            alt="loading along the blade",
            style=("perf_computing ? 'width: 100%; opacity: 0.35' : 'width: 100%'",),
        )
        html.Div(
            SOLVER_LABEL,
            classes="text-caption text-medium-emphasis mx-3 mb-2",
            id="performance-label",
        )


def _toolbar(studio: Studio, layout: SinglePageWithDrawerLayout) -> None:
    layout.title.set_text("torus_cad studio")
    with layout.toolbar:
        v3.VSpacer()
        v3.VChip("{{ status }}", id="status", classes="mr-2", color=(_STATUS_COLOR,))
        v3.VProgressCircular(
            v_if=("building",), indeterminate=True, size=20, width=2, classes="mr-2"
        )
        v3.VSwitch(
            v_model=("show_sections",),
            label="section curves",
            hide_details=True,
            density="compact",
            color="primary",
            classes="mx-2 flex-grow-0",
            id="toggle-sections",
        )
        v3.VBtn(
            icon="mdi-crop-free",
            click=studio.reset_view,
            variant="text",
            title="reset the view",
            id="reset-view",
        )


def _view_area(studio: Studio) -> None:
    with html.Div(style="flex: 1 1 auto; position: relative; min-width: 0;"):
        v3.VAlert(
            "{{ refusal }}",
            v_if=("refusal",),
            type="error",
            density="compact",
            variant="tonal",
            id="refusal",
            classes="studio-refusal",
            title="refused; the last good propeller stays on screen",
            style="position: absolute; top: 8px; left: 8px; right: 8px; z-index: 2;",
        )
        v3.VAlert(
            "{{ failure }}",
            v_if=("failure",),
            type="warning",
            density="compact",
            variant="tonal",
            id="failure",
            style="position: absolute; bottom: 8px; left: 8px; right: 8px; z-index: 2;",
        )
        # Rendered in the browser (WebGL): orbit, zoom and pan need no round trip, and the server
        # renders nothing (rendering on the server, in software, is much slower: the docs'
        # measurements page).
        view = vtk_widgets.VtkLocalView(studio.view.window, id="view", ref="view")
        studio.ctrl.view_update = view.update
        studio.ctrl.view_push_camera = view.push_camera


def build_layout(studio: Studio) -> None:
    """Build the page of ``studio``."""
    with SinglePageWithDrawerLayout(studio.server, full_height=True) as layout:
        layout.root.theme = "light"
        html.Style(_CSS)
        _toolbar(studio, layout)
        layout.footer.hide()
        layout.drawer.width = DRAWER_WIDTH
        with layout.drawer:
            with html.Div(classes="pa-2"):
                v3.VFileInput(
                    v_model=("upload_file", None),
                    label="open a design (TOML, with its .dat files)",
                    accept=".toml,.dat,.txt",
                    multiple=True,
                    density="compact",
                    variant="outlined",
                    prepend_icon="mdi-folder-open",
                    error_messages=("upload_error || []",),
                    hide_details="auto",
                    id="upload",
                    messages=("upload_message",),
                )
            parameter_panel(studio.groups)
        with (
            layout.content,
            v3.VContainer(fluid=True, classes="fill-height pa-0"),
            html.Div(style="display: flex; width: 100%; height: calc(100vh - 64px);"),
        ):  # below the toolbar
            _view_area(studio)
            with html.Div(style="flex: 0 0 330px; overflow-y: auto;", id="readouts-column"):
                _readouts()
                _performance()
