"""TEMPORARY (until torus_cad.parameters lands): spec-like records from the old dataclasses."""
import dataclasses
from types import SimpleNamespace

from torus_cad.geometry import parameters as old


def specs():
    out = []
    def walk(obj, prefix):
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value):
                walk(value, prefix + f.name + ".")
                continue
            key = prefix + f.name
            kind = type(value)
            out.append(SimpleNamespace(key=key, kind=kind, default=value, unit="", doc=old._COMMENTS.get(key, ""),
                bounds=SimpleNamespace(low=1 if key=="blades" else None, high=12 if key=="blades" else None, low_open=False, high_open=False),
                length=len(value) if isinstance(value, tuple) else 0, fuzz=None, choices=()))
    walk(old.PropellerParameters(), "")
    return out
