"""The import layers: the runtime (the ground floor) imports nothing of the package but the errors
and the tolerances; geometry imports no CAD kernel and nothing above it, and inside it section, hub,
blade and analysis each import only the layers below; the kernel imports no pipeline or app; nothing
imports the CLI. Read from the sources' import statements, and checked once more in a fresh
interpreter for the geometry layer."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parent.parent / "torus_cad"
KERNEL_PACKAGES = {"OCP", "cadquery", "OCC", "build123d"}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> set[str]:
    """Every module a source file imports (absolute names; relative imports resolved)."""
    names: set[str] = set()
    package = _module_name(path).rsplit(".", 0 if path.stem == "__init__" else 1)[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(
                    package.split(".")[: len(package.split(".")) - node.level + 1]
                    + ([base] if base else [])
                )
            names.add(base)
            names.update(f"{base}.{alias.name}" for alias in node.names)
    return names


def _sources(subpackage: str = "") -> list[Path]:
    return sorted((PACKAGE / subpackage).rglob("*.py"))


def _offenders(sources: list[Path], forbidden: callable) -> list[str]:  # type: ignore[valid-type]
    return [
        f"{path.relative_to(PACKAGE.parent)}: {name}"
        for path in sources
        for name in sorted(_imports(path))
        if forbidden(name)
    ]


def test_geometry_imports_no_kernel_and_nothing_above_it():
    def forbidden(name: str) -> bool:
        top = name.split(".")[0]
        inside = name.startswith("torus_cad.") and not name.startswith(
            (
                "torus_cad.geometry",
                "torus_cad.errors",
                "torus_cad.tolerances",
                "torus_cad.runtime.input_files",
            )
        )
        return top in KERNEL_PACKAGES or inside

    assert _offenders(_sources("geometry"), forbidden) == []


def test_the_runtime_imports_only_the_errors_and_the_tolerances():
    """torus_cad.runtime is the ground floor: files, processes, isolation, signals, extras,
    progress."""

    def forbidden(name: str) -> bool:
        return name.split(".")[0] in KERNEL_PACKAGES or (
            name.startswith("torus_cad.")
            and not name.startswith(
                ("torus_cad.errors", "torus_cad.tolerances", "torus_cad.runtime")
            )
        )

    assert _offenders(_sources("runtime"), forbidden) == []


#: geometry's sub-packages, each by job, from the ground up: a layer imports only the layers before
#: it (and itself), so nothing in geometry runs back up and no two sub-packages import each other.
GEOMETRY_LAYERS = ("section", "hub", "blade", "analysis")


def test_geometry_is_sorted_into_its_layers():
    """Every geometry module sits in one of the layers (nothing loose beside them)."""
    loose = sorted(
        str(path.relative_to(PACKAGE))
        for path in _sources("geometry")
        if path.relative_to(PACKAGE / "geometry").parts[0] not in GEOMETRY_LAYERS
        and path.name != "__init__.py"
    )
    packages = sorted(
        path.name
        for path in (PACKAGE / "geometry").iterdir()
        if path.is_dir() and path.name != "__pycache__"
    )
    assert (loose, packages) == ([], sorted(GEOMETRY_LAYERS))


@pytest.mark.parametrize("layer", GEOMETRY_LAYERS)
def test_a_geometry_layer_imports_only_the_layers_below_it(layer):
    allowed = GEOMETRY_LAYERS[: GEOMETRY_LAYERS.index(layer) + 1]

    def forbidden(name: str) -> bool:
        parts = name.split(".")
        return parts[:2] == ["torus_cad", "geometry"] and len(parts) > 2 and parts[2] not in allowed

    assert _offenders(_sources(f"geometry/{layer}"), forbidden) == []


def test_geometry_modules_import_each_other_without_cycles():
    """Read from every import statement (function-local ones too): no module reaches itself."""
    modules = {_module_name(path): path for path in _sources("geometry")}
    graph = {
        name: {imported for imported in _imports(path) if imported in modules and imported != name}
        for name, path in modules.items()
    }
    cycles = []
    for start in graph:
        stack, seen = [(start, [start])], set()
        while stack:
            node, route = stack.pop()
            for following in graph[node]:
                if following == start:
                    cycles.append(" -> ".join(route + [start]))
                elif following not in seen:
                    seen.add(following)
                    stack.append((following, route + [following]))
    assert cycles == []


def test_the_untrusted_file_reader_imports_only_the_standard_library_and_the_errors():
    """torus_cad.runtime.input_files sits below the geometry layer (it reads coordinate files)."""

    def forbidden(name: str) -> bool:
        return name.split(".")[0] not in sys.stdlib_module_names | {
            "__future__"
        } and not name.startswith(("torus_cad.errors", "torus_cad.tolerances"))

    assert _offenders([PACKAGE / "runtime" / "input_files.py"], forbidden) == []


def test_kernel_imports_no_pipeline_or_app():
    def forbidden(name: str) -> bool:
        return name.startswith("torus_cad.") and not name.startswith(
            (
                "torus_cad.kernel",
                "torus_cad.geometry",
                "torus_cad.errors",
                "torus_cad.tolerances",
                "torus_cad.formats",
                "torus_cad.build_stages",  # the writers' registry times each format as a stage
                "torus_cad.runtime",
            )
        )

    assert _offenders(_sources("kernel"), forbidden) == []


def test_parameters_import_no_kernel():
    def forbidden(name: str) -> bool:
        return name.split(".")[0] in KERNEL_PACKAGES or name.startswith("torus_cad.kernel")

    assert _offenders(_sources("parameters"), forbidden) == []


def test_the_design_s_front_door_imports_no_kernel():
    """torus_cad.design turns parameters into kernel-free geometry: ``torus-cad check`` and the
    studies' pre-screen run it without OpenCascade."""

    def forbidden(name: str) -> bool:
        return name.split(".")[0] in KERNEL_PACKAGES or name.startswith("torus_cad.kernel")

    assert _offenders(_sources("design"), forbidden) == []


def test_the_schema_stands_apart_from_the_geometry_it_describes():
    """The parameters are the validated schema: what turns them into geometry (torus_cad.design)
    sits above them, and they never reach up to it."""
    assert (
        _offenders(_sources("parameters"), lambda name: name.startswith("torus_cad.design")) == []
    )


def test_nothing_imports_the_cli():
    sources = [
        path
        for path in _sources()
        if "cli" not in path.relative_to(PACKAGE).parts and path.name != "__main__.py"
    ]
    assert (
        _offenders(
            sources, lambda name: name == "torus_cad.cli" or name.startswith("torus_cad.cli.")
        )
        == []
    )


#: The applications on top of the core, each a package by concept.
APPS = ("cli", "preview", "studio", "mesh", "cfd_domain", "batch", "simulate", "optimize", "vortex")


def test_the_core_imports_no_app():
    """geometry, kernel, parameters, outputs, runtime and the pipeline are usable without any
    command."""
    core = [
        path
        for path in _sources()
        if path.relative_to(PACKAGE).parts[0] not in APPS and path.name != "__main__.py"
    ]
    assert (
        _offenders(core, lambda name: name.startswith(tuple(f"torus_cad.{app}" for app in APPS)))
        == []
    )


def test_the_package_root_holds_only_the_core_s_face():
    """The pipeline and its stages, the exceptions, the tolerances, the shared enums and colours;
    the rest lives in packages."""
    loose = sorted(path.name for path in PACKAGE.glob("*.py"))
    assert loose == [
        "__init__.py",
        "__main__.py",
        "build_stages.py",
        "colors.py",
        "errors.py",
        "formats.py",
        "propeller.py",
        "tolerances.py",
    ]


# mesh: without --compare, no kernel
@pytest.mark.parametrize("package", ["geometry", "parameters", "design", "mesh"])
def test_importing_a_kernel_free_layer_loads_no_kernel_module(package):
    modules = [_module_name(path) for path in _sources(package)]
    code = (
        "import sys\n"
        + "".join(f"import {name}\n" for name in modules)
        + "loaded = sorted(m for m in sys.modules if m.split('.')[0] in {'OCP', 'cadquery'})\n"
        + "print(','.join(loaded))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=PACKAGE.parent
    )
    assert result.stdout.strip() == ""


def test_every_constant_of_the_tolerances_module_is_read_in_two_places_at_least():
    """tolerances.py holds what two or more places share (modules of the package, or a module and
    the tests or scripts that hold it to them); a constant one module alone reads lives beside
    it."""
    root = PACKAGE.parent
    tree = ast.parse((PACKAGE / "tolerances.py").read_text())
    names = [
        target.id
        for node in tree.body
        if isinstance(node, (ast.Assign, ast.AnnAssign))
        for target in ([node.target] if isinstance(node, ast.AnnAssign) else node.targets)
        if isinstance(target, ast.Name) and target.id.isupper()
    ]
    sources = [
        path
        for folder in ("torus_cad", "tests", "scripts", "studies")
        for path in (root / folder).rglob("*.py")
        if path != PACKAGE / "tolerances.py"
    ]
    words = {path: set(ast.walk(ast.parse(path.read_text()))) for path in sources}
    readers = {
        name: [
            path
            for path, nodes in words.items()
            if any(
                (isinstance(node, ast.Name) and node.id == name)
                or (isinstance(node, ast.Attribute) and node.attr == name)
                or (isinstance(node, ast.alias) and node.name == name)
                or (isinstance(node, ast.Constant) and node.value == name)
                for node in nodes
            )
        ]
        for name in names
    }
    lonely = {
        name: [str(path.relative_to(root)) for path in paths]
        for name, paths in readers.items()
        if len(paths) < 2
    }
    assert names and not lonely, f"constants read in fewer than two places: {lonely}"
