"""The designs of a sweep: a grid, random samples or a Latin hypercube, each named by a hash of its
parameters.

Every design gets an id, the first :data:`ID_LENGTH` hex digits of the SHA-256 of its
canonical JSON parameter dict (sorted keys, without ``name``, which is set to the id), so the
same parameters always get the same id and folder, whichever sweep asks for them.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from torus_cad.batch.sweep_file import SweepMode, SweepSpec, VaryAxis

__all__ = [
    "ID_LENGTH",
    "Design",
    "apply_axis_values",
    "design_id",
    "generate_designs",
    "unit_samples",
]

ID_LENGTH = 12  #: hex digits of the SHA-256 kept as the design id (48 bits)


@dataclass(frozen=True)
class Design:
    """One variant of the sweep.

    Attributes:
        index: its position in the sweep (0-based), the table's row order.
        design_id: the short SHA-256 of its parameters (see :func:`design_id`).
        varied: the varied values by ``[vary]`` key.
        parameters: the full parameter dict (the TOML layout), ``name`` set to the id; not yet
            validated, so a value the schema refuses is recorded when the design runs.
    """

    index: int
    design_id: str
    varied: dict[str, Any]
    parameters: dict[str, Any]


def design_id(parameters: Mapping[str, Any]) -> str:
    """First :data:`ID_LENGTH` hex digits of the SHA-256 of the canonical JSON of ``parameters``.

    Canonical: sorted keys, no spaces, tuples as lists, the ``name`` key left out (it only
    names the files, and a design's files are named by this id).
    """
    data = {key: value for key, value in parameters.items() if key != "name"}
    text = json.dumps(data, sort_keys=True, separators=(",", ":"), default=list, allow_nan=False)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:ID_LENGTH]


def unit_samples(mode: SweepMode, samples: int, dimensions: int, seed: int) -> np.ndarray:
    """``(samples, dimensions)`` points in [0, 1): uniform (random) or a Latin hypercube, from
    ``seed``."""
    rng = np.random.default_rng(seed)
    if mode is SweepMode.RANDOM:
        return rng.random((samples, dimensions))
    from scipy.stats import qmc

    try:
        sampler = qmc.LatinHypercube(d=dimensions, rng=rng)
    except TypeError:  # scipy < 1.15 names it seed
        sampler = qmc.LatinHypercube(d=dimensions, seed=rng)
    return sampler.random(samples)


def _combinations(spec: SweepSpec) -> Iterator[tuple[Any, ...]]:
    """The varied values of each design, in order (one value per axis)."""
    if spec.mode is SweepMode.GRID:
        yield from itertools.product(*(axis.values for axis in spec.axes))
        return
    assert spec.samples is not None
    units = unit_samples(spec.mode, spec.samples, max(1, len(spec.axes)), spec.seed)
    for row in units:
        yield tuple(axis.pick(float(u)) for axis, u in zip(spec.axes, row))


def apply_axis_values(
    base: Mapping[str, Any], axes: Iterable[VaryAxis], combination: tuple[Any, ...]
) -> dict[str, Any]:
    """A deep copy of ``base`` with each axis's value set.

    Args:
        base: a design's parameters as nested tables (:meth:`PropellerParameters.to_dict`); not
            changed.
        axes: the varied parameters, each naming its table path (and vector element, if any).
        combination: one value per axis, in the order of ``axes``.

    Returns:
        The new parameters: ``base`` copied, with each axis's parameter (or vector element) set to
            its value.
    """
    parameters = copy.deepcopy(dict(base))
    for axis, value in zip(axes, combination):
        table = parameters
        for part in axis.path[:-1]:
            table = table[part]
        if axis.index is None:
            table[axis.path[-1]] = value
        else:
            table[axis.path[-1]][axis.index] = value
    return parameters


def generate_designs(spec: SweepSpec) -> list[Design]:
    """Every design of the sweep, in order, duplicates (same id) dropped after their first
    appearance."""
    base = spec.base.to_dict()
    designs: list[Design] = []
    seen: set[str] = set()
    for combination in _combinations(spec):
        parameters = apply_axis_values(base, spec.axes, combination)
        ident = design_id(parameters)
        if ident in seen:
            continue
        seen.add(ident)
        parameters["name"] = ident
        designs.append(
            Design(
                len(designs),
                ident,
                {axis.key: value for axis, value in zip(spec.axes, combination)},
                parameters,
            )
        )
    return designs
