"""Optional extras: the modules each one installs, and the one line that names a missing one.

Every command that needs an extra calls :func:`require_extra` before it reads or writes anything, so
a machine without the extra gets one line (the extra and its install command), exit code 2 and no
file, instead of a ``ModuleNotFoundError`` half-way through. The install line pins versions with the
repository's ``constraints.txt``, as the README's own install line does.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Iterable

from torus_cad.errors import MissingExtraError

#: The modules a command needs from each extra of pyproject.toml (import names, not distribution
#: names). Modules an extra installs for one option only (cmaes for the CMA-ES sampler, psycopg2 for
#: PostgreSQL, dask.distributed for --scheduler, pyarrow for Parquet tables) are required where that
#: option is chosen.
EXTRA_MODULES: dict[str, tuple[str, ...]] = {
    "mesh": ("manifold3d", "meshio"),
    "cfd": ("gmsh",),
    "simulate": ("gmsh", "foamlib"),
    "optimize": ("optuna",),
    "sweep": ("dask.distributed",),
    "studio": ("trame", "trame_vtk", "trame_vuetify"),
    "docs": ("mkdocs", "material", "mkdocstrings_handlers"),
}

#: Modules an extra installs that only some options use: their extra, for the message of a late
#: import.
OPTIONAL_MODULES: dict[str, str] = {
    "cmaes": "optimize",
    "psycopg2": "optimize",
    "optuna_dashboard": "optimize",
    "pyarrow": "sweep",
    "dask": "sweep",
    "distributed": "sweep",
}


def install_line(extra: str | None = None) -> str:
    """The command that installs ``extra`` (or the package alone) from a clone, versions pinned."""
    target = f"'.[{extra}]'" if extra else "."
    return f"pip install -c constraints.txt -e {target}"


def missing_extra_message(command: str, extra: str, module: str) -> str:
    """One line: what needs which extra, which module is absent, the install command."""
    return f"{command} needs the {extra} extra ({module} is not installed): {install_line(extra)}"


def is_installed(module: str) -> bool:
    """Whether ``module`` (dotted names allowed) can be found, without importing it (its parent
    package is imported for a dotted name)."""
    try:
        return importlib.util.find_spec(module) is not None
    # a parent package missing, or a module set to None in sys.modules
    except (ImportError, ValueError):
        return False


def require_extra(command: str, extra: str, modules: Iterable[str] | None = None) -> None:
    """MissingExtraError (exit 2, one line) unless every module of ``extra`` (or ``modules``) is
    installed.

    ``command``: how the message names what needs them, e.g. ``"mesh"`` (the line starts "torus-cad:
    ").
    """
    for module in EXTRA_MODULES[extra] if modules is None else modules:
        if not is_installed(module):
            raise MissingExtraError(missing_extra_message(command, extra, module))


def extra_of_module(module: str) -> str | None:
    """The extra that installs ``module`` (a top-level or dotted import name), or None for the base
    package."""
    top = module.split(".")[0]
    for extra, modules in EXTRA_MODULES.items():
        if any(name.split(".")[0] == top for name in modules):
            return extra
    return OPTIONAL_MODULES.get(top)
