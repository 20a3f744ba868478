"""scripts/cq_editor_propeller.py: shows one valid solid in cq-editor, writes files as plain
python."""

from __future__ import annotations

import ast
import runpy
import types
from pathlib import Path

import cadquery as cq
import pytest

from torus_cad.kernel.checks import is_valid_closed_solid
from torus_cad.kernel.mass_properties import precise_volume
from torus_cad.kernel.step_readback import read_step
from torus_cad.parameters import PropellerParameters
from torus_cad.tolerances import READ_BACK_RELATIVE_TOLERANCE

SCRIPT = Path(__file__).resolve().parent.parent / "scripts" / "cq_editor_propeller.py"


class ShowObjectRecorder:
    """Stands in for cq-editor's ``show_object(obj, name=None, options=None, **kwargs)``."""

    def __init__(self) -> None:
        self.calls: list[tuple[object, str | None, dict]] = []

    def __call__(
        self, obj: object, name: str | None = None, options: dict | None = None, **kwargs: object
    ) -> None:
        self.calls.append((obj, name, {**(options or {}), **kwargs}))


def _run_like_cq_editor(recorder: ShowObjectRecorder) -> dict:
    """What cq-editor does: compile the text, exec it in a fresh module with show_object injected
    (no ``__file__``, ``__name__`` not ``__main__``)."""
    code = compile(SCRIPT.read_text(), "<string>", "exec")
    module = types.ModuleType("temp")
    module.__dict__["show_object"] = recorder
    module.__dict__["debug"] = lambda *args, **kwargs: None
    exec(code, module.__dict__, module.__dict__)
    return module.__dict__


def _run_with_runpy(recorder: ShowObjectRecorder) -> dict:
    return runpy.run_path(str(SCRIPT), init_globals={"show_object": recorder})


@pytest.mark.parametrize(
    "runner", [_run_like_cq_editor, _run_with_runpy], ids=["cq-editor-exec", "runpy"]
)
def test_script_shows_one_valid_solid(runner, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    recorder = ShowObjectRecorder()
    namespace = runner(recorder)
    assert len(recorder.calls) == 1
    shown, name, _ = recorder.calls[0]
    assert name == "torus_propeller"
    assert isinstance(shown, cq.Workplane)
    solids = [value for value in shown.vals() if isinstance(value, cq.Shape)]
    assert len(solids) == 1
    assert is_valid_closed_solid(solids[0])
    assert len(solids[0].Solids()) == 1
    result = namespace["result"]
    assert precise_volume(solids[0]) == pytest.approx(precise_volume(result.solid), rel=1e-12)
    assert not (tmp_path / "step_out").exists()  # in cq-editor nothing is written


def test_plain_python_run_writes_the_files(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    namespace = runpy.run_path(str(SCRIPT), run_name="__main__")
    out = tmp_path / "step_out"
    names = sorted(path.name for path in out.iterdir())
    assert names == [
        "torus_propeller.json",
        "torus_propeller.png",
        "torus_propeller.step",
        "torus_propeller.stl",
        "torus_propeller_sections.csv",
        "torus_propeller_sections.png",
    ]
    printed = capsys.readouterr().out
    assert "wrote step_out/torus_propeller.step" in printed and "mass" in printed
    shape = read_step(out / "torus_propeller.step")
    assert is_valid_closed_solid(shape)
    assert precise_volume(shape) == pytest.approx(
        precise_volume(namespace["result"].solid), rel=READ_BACK_RELATIVE_TOLERANCE
    )


def _top_constants() -> dict[str, object]:
    tree = ast.parse(SCRIPT.read_text())
    constants: dict[str, object] = {}
    for node in tree.body:
        if (
            isinstance(node, ast.Assign)
            and len(node.targets) == 1
            and isinstance(node.targets[0], ast.Name)
        ):
            try:
                constants[node.targets[0].id] = ast.literal_eval(node.value)
            except ValueError:
                continue
    return constants


def test_parameters_sit_at_the_top_and_default_to_the_built_in_design():
    source = SCRIPT.read_text()
    constants = _top_constants()
    first_import = min(source.index(word) for word in ("\nimport ", "\nfrom "))
    assert source.index("CHANGES = ") < first_import  # parameters come before any code
    assert constants["DESIGN"] is None
    # Every key is a real parameter at its default: the script builds the built-in design.
    assert PropellerParameters().with_values(constants["CHANGES"]) == PropellerParameters()


def test_edited_parameters_change_the_shown_propeller(tmp_path, monkeypatch):
    # Edit the script the way a user would (in place) and run it like cq-editor does.
    monkeypatch.chdir(tmp_path)
    text = SCRIPT.read_text().replace('"blades": 3,', '"blades": 2,')
    text = text.replace('"resolution.sections": 25,', '"resolution.sections": 12,')
    text = text.replace('"resolution.points": 80,', '"resolution.points": 40,')
    assert (
        '"blades": 2,' in text
        and '"resolution.sections": 12,' in text
        and '"resolution.points": 40,' in text
    )
    recorder = ShowObjectRecorder()
    namespace: dict = {"show_object": recorder, "__name__": "temp"}
    exec(compile(text, "<string>", "exec"), namespace)
    assert len(recorder.calls) == 1
    assert len(namespace["result"].blades) == 2
    assert is_valid_closed_solid(recorder.calls[0][0].val())


def test_a_run_after_a_build_keeps_the_builds_whole_set(tmp_path, monkeypatch):
    from torus_cad.cli import main
    from torus_cad.outputs.output_set import verify_set

    monkeypatch.chdir(tmp_path)
    assert main(["build", "--preview", "-q"]) == 0
    built = sorted(path.name for path in (tmp_path / "step_out").iterdir())
    runpy.run_path(str(SCRIPT), run_name="__main__")
    assert sorted(path.name for path in (tmp_path / "step_out").iterdir()) == built
    verify_set(tmp_path / "step_out", "torus_propeller")
