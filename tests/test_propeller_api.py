"""The CadQuery API: real CadQuery objects a CAD user can keep working with."""

from __future__ import annotations

import math
import pickle

import cadquery as cq
import numpy as np
import pytest

from torus_cad.colors import blade_color
from torus_cad.errors import ParameterError
from torus_cad.kernel.checks import is_valid_closed_solid
from torus_cad.kernel.mass_properties import precise_volume
from torus_cad.parameters import PropellerParameters, resolve_parameters
from torus_cad.propeller import Propeller, propeller_objects

FAST = {"resolution.sections": 16, "resolution.points": 40}


@pytest.fixture(scope="module")
def fast_params() -> PropellerParameters:
    return PropellerParameters().with_values({**FAST, "name": "api_fast"})


@pytest.fixture(scope="module")
def objects(fast_params) -> Propeller:
    return propeller_objects(fast_params)


def test_returns_cadquery_objects(objects, fast_params):
    assert isinstance(objects.workplane, cq.Workplane)
    assert isinstance(objects.solid, cq.Solid)
    assert isinstance(objects.hub, cq.Solid)
    assert all(isinstance(blade, cq.Solid) for blade in objects.blades)
    assert len(objects.blades) == fast_params.blades == 3
    assert objects.parameters == fast_params
    assert objects.workplane.val() is objects.solid  # the workplane holds the fused solid itself


def test_the_cadquery_solids_wrap_the_opencascade_shapes(objects):
    """``shape``, ``hub_shape``, ``blade_shapes`` are the solids the cadquery objects hold."""
    assert objects.solid.wrapped.IsSame(objects.shape) and objects.hub.wrapped.IsSame(
        objects.hub_shape
    )
    assert all(
        blade.wrapped.IsSame(shape)
        for blade, shape in zip(objects.blades, objects.blade_shapes, strict=True)
    )


def test_a_built_propeller_pickles_with_its_solids(objects):
    copy = pickle.loads(pickle.dumps(objects))
    assert copy.parameters == objects.parameters and copy.face_parts == objects.face_parts
    assert copy.solid.Volume() == pytest.approx(objects.solid.Volume(), rel=1e-12)
    assert [len(blade.Faces()) for blade in copy.blades] == [
        len(blade.Faces()) for blade in objects.blades
    ]
    assert is_valid_closed_solid(copy.solid) and len(copy.hub.Faces()) == len(objects.hub.Faces())


def test_solid_hub_and_blades_are_valid_closed_solids(objects):
    for shape in (objects.solid, objects.hub, *objects.blades):
        assert is_valid_closed_solid(shape)


def test_hub_is_the_parameters_cylinder(objects, fast_params):
    box = objects.hub.BoundingBox()
    radius, length = fast_params.hub.radius, fast_params.hub.length
    assert (box.xmin, box.xmax, box.zmin, box.zmax) == pytest.approx(
        (-radius, radius, -length / 2, length / 2), abs=1e-6
    )
    assert precise_volume(objects.hub) == pytest.approx(math.pi * radius**2 * length, rel=1e-9)


def test_blades_are_rotated_copies_at_the_pattern_angles(objects, fast_params):
    # Same volume, and blade i's centroid is blade 0's turned by 360 i / n about z.
    volumes = [precise_volume(blade) for blade in objects.blades]
    assert volumes == pytest.approx([volumes[0]] * len(volumes), rel=1e-6)
    first = np.array(objects.blades[0].Center().toTuple())
    for index, blade in enumerate(objects.blades):
        angle = math.radians(360.0 * index / fast_params.blades)
        turn = np.array(
            [
                [math.cos(angle), -math.sin(angle), 0],
                [math.sin(angle), math.cos(angle), 0],
                [0, 0, 1],
            ]
        )
        assert np.array(blade.Center().toTuple()) == pytest.approx(turn @ first, abs=1e-6)


def test_fused_solid_is_the_union_of_hub_and_blades(objects):
    union = objects.hub.fuse(*objects.blades).clean()
    assert precise_volume(objects.solid) == pytest.approx(precise_volume(union), rel=1e-6)
    hub, blade = precise_volume(objects.hub), precise_volume(objects.blades[0])
    assert hub < precise_volume(objects.solid) < hub + len(objects.blades) * blade


def test_cadquery_operations_work_on_the_workplane(objects, fast_params):
    # A CAD user's first edit: a 5 mm bore through the hub along the spin axis.
    bored = objects.workplane.faces(">Z").workplane().hole(5.0)
    solid = bored.val()
    assert is_valid_closed_solid(solid)
    removed = precise_volume(objects.solid) - precise_volume(solid)
    assert removed == pytest.approx(math.pi * 2.5**2 * fast_params.hub.length, rel=1e-6)


def test_assembly_has_named_coloured_parts(objects):
    assembly = objects.assembly()
    assert isinstance(assembly, cq.Assembly)
    assert assembly.name == "api_fast"
    names = [child.name for child in assembly.children]
    assert names == ["hub", "blade_0", "blade_1", "blade_2"]
    colours = [tuple(round(c, 4) for c in child.color.toTuple()) for child in assembly.children]
    assert len(set(colours)) == len(colours)  # every part its own colour
    part_volume = sum(precise_volume(child.obj) for child in assembly.children)
    expected = precise_volume(objects.hub) + sum(precise_volume(blade) for blade in objects.blades)
    assert part_volume == pytest.approx(expected, rel=1e-9)
    fused = objects.assembly(name="one", fused=True)
    assert [child.name for child in fused.children] == ["propeller"]
    assert precise_volume(fused.children[0].obj) == pytest.approx(
        precise_volume(objects.solid), rel=1e-12
    )


def test_assembly_exports_as_step(objects, tmp_path):
    path = tmp_path / "assembly.step"
    objects.assembly().export(str(path))
    assert path.stat().st_size > 1000


def test_accepts_a_toml_path_with_overrides(tmp_path, fast_params):
    path = tmp_path / "design.toml"
    path.write_text(fast_params.to_toml())
    built = propeller_objects(path, overrides={"blades": 2, "hub.radius": 9.0})
    assert built.parameters == fast_params.with_values({"blades": 2, "hub.radius": 9.0})
    assert len(built.blades) == 2
    assert is_valid_closed_solid(built.solid)
    assert built.hub.BoundingBox().xmax == pytest.approx(9.0, abs=1e-6)


def test_resolve_parameters_accepts_none_parameters_and_paths(tmp_path):
    assert resolve_parameters(None) == PropellerParameters()
    custom = PropellerParameters().with_values({"blades": 5})
    assert resolve_parameters(custom) is custom
    path = tmp_path / "d.toml"
    path.write_text(custom.to_toml())
    assert resolve_parameters(path) == custom
    assert resolve_parameters(str(path), {"phase_deg": 10.0}) == custom.with_values(
        {"phase_deg": 10.0}
    )


def test_bad_overrides_raise_parameter_errors_naming_the_key():
    with pytest.raises(ParameterError, match=r"hub\.raduis"):
        propeller_objects(overrides={"hub.raduis": 3.0})
    with pytest.raises(ParameterError, match="blades"):
        propeller_objects(overrides={"blades": 0})


def test_progress_callback_sees_every_stage_in_order(fast_params):
    seen: list[str] = []
    built = propeller_objects(fast_params, progress=seen.append)
    assert seen == [
        "parameters",
        "design_targets",
        "section_math",
        "wires",
        "loft",
        "fuse",
        "check",
        "strict_check",
    ]
    assert list(built.stage_seconds) == seen


def test_mass_properties_and_write_delegate_to_the_pipeline(objects, tmp_path):
    properties = objects.mass_properties(2.0)
    # both to 1e-6
    assert properties.volume_mm3 == pytest.approx(precise_volume(objects.solid), rel=1e-6)
    assert properties.mass_g == pytest.approx(2.0e-3 * properties.volume_mm3, rel=1e-12)
    paths = objects.write(tmp_path, stl=False)
    assert sorted(paths) == ["json", "step"]
    assert all(path.exists() for path in paths.values())


@pytest.mark.parametrize("blades", [1, 2, 3, 8, 9, 12])
def test_blade_colours_are_distinct(blades):
    colours = [blade_color(i, blades) for i in range(blades)]
    assert len(set(colours)) == blades
    assert all(0.0 <= c <= 1.0 for colour in colours for c in colour)
