"""Designs uploaded to the studio: read from their bytes by the same path as ``torus-cad build
FILE`` (torus_cad.parameters.config_file: byte order mark, nesting and number limits, the TOML
reader, the schema), and allowed to name only files uploaded with them or files in the folder given
with ``--files``, never another path on the server. Uploaded files are written under the studio's
own folder by their base names; nothing on the page is ever used as a path.
"""

from __future__ import annotations

import os
import re
import shutil
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from torus_cad.errors import ParameterError
from torus_cad.parameters import PropellerParameters
from torus_cad.parameters.config_file import parse_config_bytes
from torus_cad.tolerances import AIRFOIL_FILE_MAX_BYTES

#: Largest design file accepted from the page, bytes.
MAX_UPLOAD_BYTES = 256 * 1024

#: Largest other file (a coordinate file) uploaded with a design, bytes: the airfoil file limit.
MAX_UPLOAD_FILE_BYTES = AIRFOIL_FILE_MAX_BYTES

#: Most files one upload may hold (the design and the files it names).
MAX_UPLOAD_FILES = 8

#: The names an uploaded file may have (its base name; it is stored under the studio's folder).
UPLOAD_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,99}")


def is_design(upload: Any) -> bool:
    return isinstance(upload, Mapping) and str(upload.get("name", "")).lower().endswith(".toml")


def upload_files(uploads: Sequence[Any]) -> dict[str, bytes]:
    """The uploaded files by base name; ParameterError unless there is one design (.toml) and every
    file has a plain name and is within its size limit."""
    if len(uploads) > MAX_UPLOAD_FILES:
        raise ParameterError(
            f"the upload holds {len(uploads)} files; at most {MAX_UPLOAD_FILES} (a design and the "
            "files it names)"
        )
    files: dict[str, bytes] = {}
    for upload in uploads:
        content = upload.get("content") if isinstance(upload, Mapping) else None
        if not isinstance(content, (bytes, bytearray, memoryview)):
            raise ParameterError("the uploaded file could not be read")
        name = Path(str(upload.get("name", ""))).name
        if not UPLOAD_NAME.fullmatch(name) or name in files:
            raise ParameterError(
                f"an uploaded file's name must be letters, digits, '.', '_' or '-' (at most 100, "
                f"each name once), got {name[:100]!r}"
            )
        limit = MAX_UPLOAD_BYTES if is_design(upload) else MAX_UPLOAD_FILE_BYTES
        if len(content) > limit:
            raise ParameterError(
                f"the uploaded file {name!r} is {len(content):,} bytes; at most {limit:,} bytes"
            )
        files[name] = bytes(content)
    designs = [name for name in files if name.lower().endswith(".toml")]
    if len(designs) != 1:
        raise ParameterError(
            f"an upload holds one design (.toml) and the files it names; this one holds "
            f"{len(designs)} .toml files"
        )
    return files


def read_upload(
    uploads: Sequence[Any], folder: Path, file_keys: Sequence[str], files_folder: Path | None
) -> PropellerParameters:
    """The design of an upload (one TOML file and the files it names), read as ``torus-cad build
    FILE`` reads it.

    The files are written to ``folder`` (new) under their base names; the design may name, in its
    fields ``file_keys`` (dotted keys), only them or files in ``files_folder``. The folder of a
    refused upload is removed.
    """
    files = upload_files(uploads)
    folder.mkdir(parents=True)
    try:
        for name, data in files.items():
            with open(
                os.open(folder / name, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600), "wb"
            ) as handle:
                handle.write(data)
        design_name = next(name for name in files if name.lower().endswith(".toml"))
        table = parse_config_bytes(files[design_name], design_name, "uploaded design")
        table = _only_uploaded_files(
            table, folder, set(files) - {design_name}, file_keys, files_folder
        )
        return PropellerParameters.from_table(table, folder)
    # named by the uploaded file's own name, not the server's folder
    except ParameterError as error:
        shutil.rmtree(folder, ignore_errors=True)
        raise ParameterError(str(error).replace(f"{folder}{os.sep}", "")) from None
    except BaseException:
        shutil.rmtree(folder, ignore_errors=True)
        raise


def _only_uploaded_files(
    table: dict[str, Any],
    folder: Path,
    uploaded: set[str],
    file_keys: Sequence[str],
    files_folder: Path | None,
) -> dict[str, Any]:
    """``table`` with each file it names made the path of an uploaded file (or one in
    ``files_folder``); ParameterError for any other path, before anything opens it."""
    table = {**table}
    for key in file_keys:
        *parents, leaf = key.split(".")
        holder: Any = table
        for part in parents:
            holder = holder.get(part) if isinstance(holder, dict) else None
        if not isinstance(holder, dict) or not holder.get(leaf):
            continue
        holder[leaf] = str(_allowed_file(key, holder[leaf], folder, uploaded, files_folder))
    return table


def _allowed_file(
    key: str, value: Any, folder: Path, uploaded: set[str], files_folder: Path | None
) -> Path:
    if isinstance(value, str) and value in uploaded:
        return folder / value
    if isinstance(value, str) and files_folder is not None and not value.startswith("~"):
        candidate = (files_folder / value).resolve()  # an absolute value stays absolute
        if candidate.is_relative_to(files_folder) and candidate.is_file():
            return candidate
    shown = repr(value)[:120]
    where = f" or files in {str(files_folder)!r}" if files_folder is not None else ""
    raise ParameterError(
        f"{key} = {shown}: a design opened in the page may name only files uploaded with it"
        f"{where}, never a path on this machine; choose the design and the file together"
    )
