"""No module of the package reaches another module's private names.

(a) No ``from torus_cad.x import _name`` (nor a relative one): a name another module needs is
public, with a docstring. (b) No ``obj._name`` on anything but ``self`` or ``cls`` where ``_name``
is a function or method the package defines: outside code calls a class's public methods. The
standard library's public underscore names (``os._exit``, a named tuple's ``_replace`` ...) are
allowed; a third-party private name stays in its one adapter (optuna's trial tables in
torus_cad/optimize/storage.py), pinned to the version in constraints.txt.
"""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent.parent / "torus_cad"

#: Public API of the standard library that happens to start with an underscore.
STDLIB_PUBLIC = {
    "_exit",
    "_replace",
    "_asdict",
    "_fields",
    "_field_defaults",
    "_make",
    "_current_frames",
    "_getframe",
}
#: The one module that may name a third-party private module (optuna's ``_rdb``), and why.
ADAPTERS = {"torus_cad/optimize/storage.py"}  # optuna's trial tables, for a one-query count


def _private(name: str) -> bool:
    return name.startswith("_") and not name.startswith("__")


def _modules() -> list[tuple[str, ast.Module]]:
    return [
        (path.relative_to(PACKAGE.parent).as_posix(), ast.parse(path.read_text(), str(path)))
        for path in sorted(PACKAGE.rglob("*.py"))
    ]


def _defined_functions(modules: list[tuple[str, ast.Module]]) -> set[str]:
    """The private names of every function and method the package defines."""
    return {
        node.name
        for _, tree in modules
        for node in ast.walk(tree)
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and _private(node.name)
    }


def _reaches(modules: list[tuple[str, ast.Module]]) -> list[str]:
    functions = _defined_functions(modules) - STDLIB_PUBLIC
    found = []
    for where, tree in modules:
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                module = node.module or ""
                ours = node.level > 0 or module == "torus_cad" or module.startswith("torus_cad.")
                if ours:
                    found += [
                        f"{where}:{node.lineno}: from {module} import {alias.name}"
                        for alias in node.names
                        if _private(alias.name)
                    ]
                elif where not in ADAPTERS and any(_private(part) for part in module.split(".")):
                    found.append(
                        f"{where}:{node.lineno}: from {module} import "
                        "... (a third-party private module)"
                    )
            elif isinstance(node, ast.Import) and where not in ADAPTERS:
                found += [
                    f"{where}:{node.lineno}: import {alias.name} (a private module)"
                    for alias in node.names
                    if any(_private(part) for part in alias.name.split("."))
                ]
            elif (
                isinstance(node, ast.Attribute)
                and node.attr in functions
                and not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"))
            ):
                found.append(f"{where}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_no_module_reaches_another_modules_private_names():
    found = _reaches(_modules())
    assert not found, "private names used outside their module or class:\n" + "\n".join(found)


def test_the_check_finds_each_kind():
    code = (
        "from torus_cad.batch.designs import _apply\n"
        "from ..x import _y\n"
        "from optuna.storages._rdb import models\n"
        "runner._claim()\n"
        "self._claim()\n"
        "os._exit(1)\n"
        "class A:\n"
        "    def _claim(self): pass\n"
    )
    found = _reaches([("torus_cad/example.py", ast.parse(code))])
    assert [line.split(": ", 1)[0] for line in found] == [
        f"torus_cad/example.py:{n}" for n in (1, 2, 3, 4)
    ]
    assert not _reaches(
        [("torus_cad/optimize/storage.py", ast.parse("from optuna.storages._rdb import models\n"))]
    )
