"""Output sets: the files of one build (STEP, STL, picture, JSON report) appear together or not at
all.

A build is a transaction on its output folder ``OUT``:

1. **Stage.** Every file is written into a staging folder of its own,
   ``OUT/.<name>.staging-<host>-<pid>-<random>/``, that no other build touches. A failed or
   interrupted build removes it; one of a process that died (SIGKILL) is removed by the next
   build in that folder.
2. **Seal.** The JSON report is written last and lists every other file of the set with its
   size and SHA-256 (``"files"``).
3. **Publish.** Under an exclusive ``flock`` on the folder ``OUT`` itself (builds into one folder
   take turns, only for this step, which takes milliseconds) the old report is removed, the files
   are renamed onto their final names, members of the old set that the new one lacks are removed,
   and the report is renamed last. Signals wait until this is done.

So at any moment ``OUT/<name>.json`` either is absent or matches the files it lists, except
after a SIGKILL (or power loss) inside the few renames of step 3, which leaves a set that
:func:`verify_set` (``torus-cad verify OUT``) reports as incomplete, naming the file. Readers
that take the lock shared (as ``verify`` does) never see a publish in progress.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import functools
import hashlib
import json
import os
import secrets
import shutil
import tempfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Self

from torus_cad.errors import IncompleteOutputError, OutputError, ParameterError
from torus_cad.runtime.files import (
    glob_escape,
    left_by_dead_process,
    make_folders,
    owner_tag,
    removed_if_left_empty,
    removed_on_exit,
)
from torus_cad.runtime.input_files import read_untrusted_bytes
from torus_cad.runtime.interrupts import deferred
from torus_cad.tolerances import REPORT_FILE_MAX_BYTES

if TYPE_CHECKING:
    from torus_cad.outputs.build_report import BuiltPropeller
    from torus_cad.runtime.isolation import IsolatedCall

#: Key of the report that lists the set's other files: ``{kind: {"file", "bytes", "sha256"}}``.
FILES_KEY = "files"

_STAGING_MARK = ".staging-"
#: Longest wait (s) for the blade-element table (CSV and PNG), drawn in a child beside the build's
#: files.
SECTIONS_TABLE_TIME_LIMIT_S = 120.0
#: Longest wait (s) for the STEP file, written and read back in a child beside the STL: the
#: default's takes under a second, and its read-back check leaves out the costly self-interference
#: test.
STEP_WRITE_TIME_LIMIT_S = 900.0
_HASH_CHUNK_BYTES = 1 << 20

#: Writes one file of a set to the path it is given.
FileWriter = Callable[[Path], Any]


def remove_stale_staging(out_dir: Path) -> list[Path]:
    """Remove staging folders in ``out_dir`` left by dead processes of this host; return them.

    Staging folders of other hosts (a shared file system) and of live processes are left alone.
    """
    removed = []
    with contextlib.suppress(OSError):
        for entry in os.scandir(out_dir):
            prefix = entry.name[: entry.name.find(_STAGING_MARK) + len(_STAGING_MARK)]
            if (
                entry.name.startswith(".")
                and _STAGING_MARK in entry.name
                and left_by_dead_process(entry.name, prefix)
            ):
                shutil.rmtree(entry.path, ignore_errors=True)
                removed.append(Path(entry.path))
    return removed


def staging_folders(out_dir: Path) -> tuple[list[Path], list[Path]]:
    """The staging folders in ``out_dir``: those left by dead processes of this host (debris,
    removed by the next build there or by :func:`remove_stale_staging`), and the others (a build in
    progress, or one of another host sharing the folder)."""
    left: list[Path] = []
    other: list[Path] = []
    with contextlib.suppress(OSError):
        for entry in sorted(os.scandir(out_dir), key=lambda entry: entry.name):
            if entry.name.startswith(".") and _STAGING_MARK in entry.name:
                prefix = entry.name[: entry.name.find(_STAGING_MARK) + len(_STAGING_MARK)]
                (left if left_by_dead_process(entry.name, prefix) else other).append(
                    Path(entry.path)
                )
    return left, other


def describe_os_error(error: OSError, path: Path) -> str:
    """One line naming the cause and the file the user knows (the final name, not a staged one)."""
    causes = {
        errno.ENOSPC: "no space left on device",
        errno.EDQUOT: "disk quota exceeded",
        errno.EACCES: "permission denied",
        errno.EPERM: "permission denied",
        errno.EROFS: "read-only file system",
        errno.EFBIG: "file size limit exceeded",
    }
    cause = causes.get(error.errno or 0, error.strerror or str(error))
    return f"{cause} writing {str(path)!r}"


def check_writable_folder(out_dir: str | Path) -> None:
    """OutputError unless files can be created in ``out_dir`` (or, if it does not exist yet, in the
    nearest folder above it, where it would be made). Checked before building, leaves nothing
    behind."""
    out_dir = Path(out_dir)
    existing = out_dir
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise OutputError(
            f"cannot write to output folder {str(out_dir)!r}: {str(existing)!r} is not a folder"
        )
    try:
        probe = tempfile.mkdtemp(prefix=".torus-cad-probe-", dir=existing)
        os.rmdir(probe)
    except OSError as error:
        cause = describe_os_error(error, existing).rsplit(" writing ", 1)[0]
        raise OutputError(f"cannot write to output folder {str(out_dir)!r}: {cause}") from None


def file_entry(path: Path) -> dict[str, Any]:
    """``{"file", "bytes", "sha256"}`` of one file of a set."""
    digest = hashlib.sha256()
    size = 0
    with open(path, "rb") as handle:
        while chunk := handle.read(_HASH_CHUNK_BYTES):
            digest.update(chunk)
            size += len(chunk)
    return {"file": path.name, "bytes": size, "sha256": digest.hexdigest()}


@contextlib.contextmanager
def _folder_lock(out_dir: Path, shared: bool = False) -> Iterator[None]:
    """Hold ``flock`` on the folder ``out_dir`` itself (no lock file is left behind).

    Where the folder cannot be locked (a file system without flock on folders, e.g. some network
    file systems) this goes on unlocked: the sealed report still tells a mixed set.
    """
    try:
        descriptor = os.open(out_dir, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        yield
        return
    try:
        with contextlib.suppress(OSError):
            fcntl.flock(descriptor, fcntl.LOCK_SH if shared else fcntl.LOCK_EX)
        yield
    finally:
        os.close(descriptor)  # releases the lock


def _read_report(path: Path) -> dict[str, Any] | None:
    """The JSON report at ``path``, or None if it is not one (not a regular file, over the limit,
    not JSON, nested too deep for the JSON reader)."""
    try:
        report = json.loads(
            read_untrusted_bytes(path, "report", REPORT_FILE_MAX_BYTES).decode("utf-8")
        )
    except (ParameterError, ValueError, RecursionError):
        return None
    return report if isinstance(report, dict) else None


class OutputSet:
    """The files of one build of ``name`` into ``out_dir``, staged and then published together.

    ::

        with OutputSet(out_dir, "torus_propeller") as output:
            write_step(solid, output.stage("step"), ...)  # writers write to the path they are given
            paths = output.publish(report)                # {kind: final path}, the report last

    Leaving the block without publishing (an error, an interrupt) removes everything staged.
    """

    def __init__(self, out_dir: str | Path, name: str) -> None:
        self.out_dir = Path(out_dir)
        self.name = name
        self.staging: Path | None = None
        self._staged: dict[str, Path] = {}
        self._cleanup: contextlib.ExitStack | None = None
        #: The report as :meth:`publish` wrote it, ``"files"`` included.
        self.sealed_report: dict[str, Any] = {}

    def __enter__(self) -> Self:
        try:
            self._cleanup = contextlib.ExitStack()
            # a folder made here and left empty (an error, a signal) is removed again: no empty
            # --out
            self._cleanup.enter_context(removed_if_left_empty(make_folders(self.out_dir)))
            remove_stale_staging(self.out_dir)
            self.staging = (
                self.out_dir / f".{self.name}{_STAGING_MARK}{owner_tag()}{secrets.token_hex(4)}"
            )
            self._cleanup.enter_context(removed_on_exit(self.staging))
            self.staging.mkdir()
        except OSError:
            self._discard()
            # the folder itself: checked before the build on the command line
            # (check_writable_folder)
            raise
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._discard()

    def _discard(self) -> None:
        if self.staging is not None:
            shutil.rmtree(self.staging, ignore_errors=True)
        if self._cleanup is not None:
            self._cleanup.close()
        self.staging, self._cleanup = None, None

    def final_path(self, kind: str) -> Path:
        """Where the file of ``kind`` is published: ``<name>.<kind>`` ("step", "stl", "3mf", "png"),
        or the name it was staged under (see :meth:`write_files`)."""
        if kind in self._staged:
            return self.out_dir / self._staged[kind].name
        return self.out_dir / f"{self.name}.{kind}"

    def stage(self, kind: str) -> Path:
        """The staging path to write the file of ``kind`` (``<name>.<kind>``) to."""
        if self.staging is None:
            raise RuntimeError("OutputSet.stage() outside its with-block")
        if kind == "json":
            raise ValueError("the JSON report is written by publish()")
        self._staged[kind] = self.staging / f"{self.name}.{kind}"
        return self._staged[kind]

    def write(self, kind: str, writer: FileWriter) -> Path:
        """Stage the file of ``kind`` with ``writer(path)``; an OSError (no space left, permission
        denied, file size limit) becomes an OutputError naming the final file and the cause."""
        path = self.stage(kind)
        with self._naming_failures(self.final_path(kind)):
            writer(path)
        if not path.is_file():
            raise OutputError(f"{str(self.final_path(kind))!r} was not written")
        return path

    def write_files(self, writer: Callable[[Path], Mapping[str, Path]]) -> None:
        """Stage files of names of their own: ``writer(folder)`` writes them into the staging folder
        and returns ``{kind: path}`` (e.g. ``<name>_sections.csv``); they join the set."""
        if self.staging is None:
            raise RuntimeError("OutputSet.write_files() outside its with-block")
        with self._naming_failures(self.out_dir):
            written = writer(self.staging)
        for kind, path in written.items():
            if Path(path).parent != self.staging or not Path(path).is_file() or kind == "json":
                raise OutputError(
                    f"{str(self.out_dir / Path(path).name)!r} was not written into the set"
                )
            self._staged[kind] = Path(path)

    @contextlib.contextmanager
    def _naming_failures(self, final: Path) -> Iterator[None]:
        try:
            yield
        except OSError as error:
            named = Path(error.filename).name if error.filename else None
            raise OutputError(
                describe_os_error(error, self.out_dir / named if named else final)
            ) from None

    def publish(self, report: Mapping[str, Any]) -> dict[str, Path]:
        """Seal the staged files into ``report`` (as its ``"files"``), write it, publish the set;
        return ``{kind: final path}`` with ``"json"`` last."""
        if self.staging is None:
            raise RuntimeError("OutputSet.publish() outside its with-block")
        files = {kind: file_entry(path) for kind, path in self._staged.items()}
        self.sealed_report = {**report, FILES_KEY: files}
        staged_report = self.staging / f"{self.name}.json"
        try:
            staged_report.write_text(
                json.dumps(self.sealed_report, indent=2, allow_nan=False) + "\n", encoding="utf-8"
            )
        except OSError as error:
            raise OutputError(describe_os_error(error, self.final_path("json"))) from None
        with deferred(), _folder_lock(self.out_dir):
            self._swap_in(staged_report)
        return {
            **{kind: self.final_path(kind) for kind in self._staged},
            "json": self.final_path("json"),
        }

    def _old_members_left(self, old_files: Mapping[str, Any]) -> list[str]:
        """Files of the old set that the new one does not have (only names of this set: a report
        cannot make us remove anything else)."""
        new_names = {path.name for path in self._staged.values()}
        names = [entry.get("file") for entry in old_files.values() if isinstance(entry, dict)]
        return [
            name
            for name in names
            if isinstance(name, str)
            and name not in new_names
            and "/" not in name
            and name.startswith((f"{self.name}.", f"{self.name}_"))
            and name != f"{self.name}.json"
        ]

    def _swap_in(self, staged_report: Path) -> None:
        report_path = self.final_path("json")
        old = _read_report(report_path)
        old_files = old.get(FILES_KEY) if old else None
        try:
            # from here until the last rename the set is visibly incomplete
            report_path.unlink(missing_ok=True)
            for kind, path in self._staged.items():
                os.replace(path, self.final_path(kind))
            if isinstance(old_files, dict):
                for stale in self._old_members_left(old_files):
                    (self.out_dir / stale).unlink(missing_ok=True)
            os.replace(staged_report, report_path)
        except OSError as error:
            raise OutputError(
                f"publishing the output set {self.name!r} in {str(self.out_dir)!r} failed: "
                f"{error.strerror}; 'torus-cad verify' reports what is there"
            ) from None


# -- checking a published set ---------------------------------------------------------------------


@dataclass(frozen=True)
class VerifiedSet:
    """A complete output set: its report and the files it lists (final paths, report last)."""

    name: str
    report: Path
    files: tuple[Path, ...]


def verify_set(out_dir: str | Path, name: str) -> VerifiedSet:
    """Check that ``out_dir/<name>.json`` and every file it lists are there, whole and of the same
    build.

    Raises IncompleteOutputError naming every file that is missing or different (its ``problems``).
    """
    out_dir = Path(out_dir)
    report_path = out_dir / f"{name}.json"
    with _folder_lock(out_dir, shared=True):
        if not report_path.is_file():
            orphans = sorted(
                p.name
                for p in out_dir.glob(f"{glob_escape(name)}.*")
                # not a set whose name goes on, "a.v2"
                if "." not in p.name[len(name) + 1 :]
            )
            if orphans:
                raise IncompleteOutputError(
                    f"{name}: incomplete set: {report_path.name} is missing beside "
                    f"{', '.join(orphans)}"
                )
            raise IncompleteOutputError(
                f"{name}: no output set {report_path.name} in {str(out_dir)!r}"
            )
        report = _read_report(report_path)
        if report is None:
            raise IncompleteOutputError(f"{name}: {report_path.name} is not a readable JSON report")
        files = report.get(FILES_KEY)
        if not isinstance(files, dict) or not files:
            raise IncompleteOutputError(
                f"{name}: {report_path.name} lists no files (written before "
                f"output sets were sealed?)"
            )
        checked: list[Path] = []
        problems: list[str] = []
        for entry in files.values():
            try:
                checked.append(_check_entry(out_dir, name, report_path.name, entry))
            except IncompleteOutputError as error:
                problems.extend(error.problems)
        if problems:
            raise IncompleteOutputError(*problems)
    return VerifiedSet(name, report_path, (*checked, report_path))


def _check_entry(out_dir: Path, name: str, report_name: str, entry: Any) -> Path:
    if (
        not isinstance(entry, dict)
        or not isinstance(entry.get("file"), str)
        or "/" in entry["file"]
    ):
        raise IncompleteOutputError(
            f"{name}: {report_name} has a malformed file entry (expected a table of "
            "file, bytes and sha256)"
        )
    path = out_dir / entry["file"]
    if not path.is_file():
        raise IncompleteOutputError(f"{name}: incomplete set: {path.name} is missing")
    actual = file_entry(path)
    if actual["bytes"] != entry.get("bytes") or actual["sha256"] != entry.get("sha256"):
        raise IncompleteOutputError(
            f"{name}: mixed set: {path.name} is not the file {report_name} was "
            f"written with (size or SHA-256 differs)"
        )
    return path


def set_names(out_dir: str | Path) -> list[str]:
    """Names of the output sets in ``out_dir``: every sealed ``<name>.json`` report, and every
    ``<name>.step`` or ``<name>.stl`` that no sealed report lists (one without its report is an
    incomplete set; a mesh set's ``<name>_mesh_ascii.stl`` is a member of ``<name>_mesh``)."""
    names: set[str] = set()
    members: set[object] = set()
    loose: set[Path] = set()
    for path in Path(out_dir).iterdir():
        if path.name.startswith(".") or not path.is_file():
            continue
        report = _read_report(path) if path.suffix == ".json" else None
        if report is not None and FILES_KEY in report:
            names.add(path.stem)
            files = report[FILES_KEY]
            members.update(
                entry.get("file")
                for entry in (files.values() if isinstance(files, dict) else ())
                if isinstance(entry, dict)
            )
        elif path.suffix in (".step", ".stl"):
            loose.add(path)
    names.update(path.stem for path in loose if path.name not in members)
    return sorted(names)


def set_folders(root: str | Path) -> list[Path]:
    """``root`` and every folder under it, sorted, that holds an output set (see :func:`set_names`).

    Hidden folders (a build's ``.<name>.staging-...``) and OpenFOAM case folders
    (:func:`is_case_folder`) are not entered; symbolic links to folders are not followed.
    """
    found = []
    for folder, subfolders, _ in os.walk(root):
        subfolders[:] = sorted(
            name
            for name in subfolders
            if not name.startswith(".") and not is_case_folder(Path(folder) / name)
        )
        if set_names(folder):
            found.append(Path(folder))
    return found


def is_case_folder(folder: str | Path) -> bool:
    """Whether ``folder`` is an OpenFOAM case (it holds ``system/controlDict``): its files (the
    surface's STL among them) belong to the case, not to output sets of their own."""
    return (Path(folder) / "system" / "controlDict").is_file()


def folders_under(root: str | Path) -> list[Path]:
    """``root`` and every folder under it but hidden ones (staging folders), sorted; links not
    followed."""
    found = []
    for folder, subfolders, _ in os.walk(root):
        subfolders[:] = sorted(name for name in subfolders if not name.startswith("."))
        found.append(Path(folder))
    return found


# -- the propeller's set --------------------------------------------------------------------------


@dataclass(frozen=True)
class PublishedSet:
    """What a build published: the final paths by kind (the report last) and the report as written.

    Read the report from here, not from ``paths["json"]``: a later build of the same name may
    already have replaced the file."""

    paths: dict[str, Path]
    report: dict[str, Any]


def _collected(
    call: IsolatedCall[dict[str, Any] | None],
) -> Callable[[Path], dict[str, Any] | None]:
    """A writer that collects ``call``'s result: the child wrote the file at its staging path
    already."""
    return lambda _path: call.result(STEP_WRITE_TIME_LIMIT_S)


def write_output_set(
    propeller: BuiltPropeller,
    out_dir: str | Path,
    density_g_cm3: float,
    stl: bool = True,
    sections_table: bool | IsolatedCall[dict[str, tuple[str, bytes]]] = False,
    extra_files: Mapping[str, FileWriter] | None = None,
) -> PublishedSet:
    """Write the files of ``export.formats`` (STEP, STL unless ``stl`` is False, 3MF), the
    blade-element table (``<name>_sections.csv`` and ``.png``, if ``sections_table``: True, or its
    files' call already started,
    :func:`torus_cad.outputs.sections_table.design_sections_table_files`), any ``extra_files``
    (``{suffix: writer(path)}``, e.g. a preview picture) and the sealed ``<name>.json`` report as
    one output set (see the module doc); return the final paths by kind (the report last) and the
    report.

    A mesh (STL, 3MF) over its triangle budget is refused before anything is written.
    """
    from torus_cad import __version__
    from torus_cad.build_stages import Stage
    from torus_cad.design.stl_budget import check_stl_budget
    from torus_cad.kernel.uncrossed import UncrossedMesh, uncrossed_mesh
    from torus_cad.kernel.writers import WRITERS, ExportJob
    from torus_cad.outputs.build_report import build_report
    from torus_cad.outputs.sections_table import sections_table_files, write_files
    from torus_cad.parameters.design import ExportFormat
    from torus_cad.runtime.isolation import IsolatedCall
    from torus_cad.runtime.stage_timer import StageTimer

    params = propeller.parameters
    export = params.export
    formats = [fmt for fmt in export.formats if stl or fmt != ExportFormat.STL]
    if {ExportFormat.STL, ExportFormat.THREE_MF} & set(formats):
        check_stl_budget(params, propeller.surface, propeller.section_curves.poles.shape[:2])
    timer = StageTimer[Stage]()
    meshes: dict[str, dict[str, Any]] = {}  # each written mesh's check, for the report
    made: list[UncrossedMesh] = []

    def mesh() -> UncrossedMesh:
        """The uncrossed tessellation that the STL and the 3MF both write, made once."""
        if not made:
            made.append(
                uncrossed_mesh(
                    propeller.shape, export.stl_linear_deflection, export.stl_angular_deflection
                )
            )
        return made[0]

    job = ExportJob(
        propeller.shape,
        params.name,
        export.step_schema,
        export.stl_linear_deflection,
        export.stl_angular_deflection,
        __version__,
        mesh,
    )

    def recorded(fmt: ExportFormat, write: Callable[[Path], dict[str, Any] | None]) -> FileWriter:
        """``write``, its mesh check (if it returns one) kept for the report."""

        def written(path: Path) -> Path:
            check = write(path)
            if check is not None:
                meshes[fmt.value] = check
            return path

        return written

    with OutputSet(out_dir, params.name) as output, contextlib.ExitStack() as children:
        # The blade-element table (matplotlib) is drawn in a child meanwhile, on the second core;
        # the child returns the files' contents and this process writes them (a signal here then
        # leaves nothing behind).
        table: IsolatedCall[dict[str, tuple[str, bytes]]] | None = None
        if isinstance(sections_table, IsolatedCall):
            table = sections_table
        elif sections_table:
            table = children.enter_context(
                IsolatedCall(
                    sections_table_files, propeller.surface, params, what="the blade-element table"
                )
            )
        # A writer that runs in a child (the STEP file, written and read back into its staging path)
        # starts first, while this process writes the others (a signal kills the child before the
        # staging folder goes). Every design's STEP file is checked as OpenCascade's reader gives it
        # back (kernel.writers.step writes it again with readable edges where it reads back faulty).
        started = {
            fmt: children.enter_context(
                IsolatedCall(
                    WRITERS[fmt].write,
                    job,
                    output.stage(fmt.value),
                    what=f"writing the {fmt.name} file",
                )
            )
            for fmt in formats
            if WRITERS[fmt].in_child
        }
        for fmt in formats:
            if not WRITERS[fmt].in_child:
                with timer.stage(WRITERS[fmt].stage):
                    output.write(
                        fmt.value, recorded(fmt, functools.partial(WRITERS[fmt].write, job))
                    )
        for fmt, call in started.items():
            with timer.stage(WRITERS[fmt].stage):  # what is left of it once the others are written
                output.write(fmt.value, recorded(fmt, _collected(call)))
        if table is not None:
            # what is left of it once the meshes are written
            with timer.stage(Stage.SECTIONS_TABLE):
                output.write_files(
                    lambda folder: write_files(table.result(SECTIONS_TABLE_TIME_LIMIT_S), folder)
                )
        for kind, writer in (extra_files or {}).items():
            output.write(kind, writer)
        propeller.stage_seconds.update(timer.seconds)
        paths = output.publish(build_report(propeller, density_g_cm3, meshes))
        return PublishedSet(paths, output.sealed_report)
