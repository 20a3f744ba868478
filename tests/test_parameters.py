"""The parameter type: defaults, TOML round trip, and validation messages that name the field."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from torus_cad.errors import ParameterError
from torus_cad.geometry.blade.transforms import quartic_minimum
from torus_cad.parameters import PropellerParameters


def test_defaults_follow_the_spec_appendix(default_params):
    assert default_params.airfoil.max_camber == 0.02
    assert default_params.airfoil.camber_position == 0.4
    assert default_params.airfoil.thickness == 0.5
    assert default_params.blades == 3


def test_toml_round_trip_is_exact(tmp_path, default_params):
    path = tmp_path / "design.toml"
    path.write_text(default_params.to_toml())
    assert PropellerParameters.from_toml(path) == default_params


@settings(max_examples=30, deadline=None)
@given(
    radius=st.floats(8.0, 30.0),
    blades=st.integers(1, 6),
    camber=st.floats(0.0, 0.09),
    chord=st.floats(0.5, 10.0),
)
def test_any_valid_design_survives_toml(tmp_path_factory, radius, blades, camber, chord):
    params = PropellerParameters().with_values(
        {
            "hub.radius": radius,
            "blades": blades,
            "airfoil.max_camber": camber,
            "transforms.scale_x": [0.0, 0.0, 0.0, 0.0, chord],
        }
    )
    path = tmp_path_factory.mktemp("toml") / "design.toml"
    path.write_text(params.to_toml(comments=False))
    assert PropellerParameters.from_toml(path) == params


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"hub.radius": -1.0}, "hub.radius"),
        ({"hub.length": 2.0}, "hub.length"),
        ({"blades": 0}, "blades"),
        ({"blades": 2.5}, "blades"),
        ({"airfoil.thickness": 0.0}, "airfoil.thickness"),
        ({"airfoil.camber_position": 1.0}, "airfoil.camber_position"),
        ({"airfoil.pivot": 1.5}, "airfoil.pivot"),
        ({"centerline.p2": [1.0, 2.0]}, "centerline.p2"),
        ({"centerline.p4": [10.0, 25.0]}, "centerline.p4[1]"),
        ({"centerline.frame": "bishop"}, "centerline.frame"),
        ({"phase_deg": math.nan}, "phase_deg"),
        ({"hub.radius": math.inf}, "hub.radius"),
        ({"hub.radius": "ten"}, "hub.radius"),
        ({"airfoil.camber_normal": 1}, "airfoil.camber_normal"),
        ({"name": "a/b"}, "name"),
        ({"resolution.points": 4}, "resolution.points"),
    ],
)
def test_bad_values_name_the_field(changes, field):
    with pytest.raises(ParameterError) as raised:
        PropellerParameters().with_values(changes)
    message = str(raised.value)
    assert message.startswith(field) or f"{field}" in message
    assert "\n" not in message


def test_out_of_range_message_gives_value_and_range():
    with pytest.raises(
        ParameterError, match=r"hub.radius = -1 is out of range; allowed \[0.5, 1000\]"
    ):
        PropellerParameters().with_values({"hub.radius": -1.0})


def test_scale_must_stay_positive_inside_the_interval_not_only_at_the_ends():
    # 40 (s - 0.5)^2 - 0.1: positive at s = 0 and 1, negative around s = 0.5.
    dip = [0.0, 0.0, 40.0, -40.0, 9.9]
    with pytest.raises(ParameterError, match=r"transforms.scale_x must stay positive .* s = 0.500"):
        PropellerParameters().with_values({"transforms.scale_x": dip})


def test_quartic_minimum_is_exact():
    value, where = quartic_minimum((1.0, -2.0, 0.0, 0.0, 3.0))  # s^4 - 2 s^3 + 3, minimum at s = 1
    assert where == pytest.approx(1.0) and value == pytest.approx(2.0)


def test_symmetric_section_accepts_any_camber_position():
    params = PropellerParameters().with_values(
        {"airfoil.max_camber": 0.0, "airfoil.camber_position": 0.0}
    )
    assert params.airfoil.max_camber == 0.0


def test_unknown_key_suggests_the_closest(tmp_path):
    path = tmp_path / "typo.toml"
    path.write_text("[hub]\nraduis = 3.0\n")
    with pytest.raises(
        ParameterError, match=r"unknown key 'hub.raduis'; did you mean 'hub.radius'\?"
    ):
        PropellerParameters.from_toml(path)


@pytest.mark.parametrize(
    "content, fragment",
    [
        (b"", "is empty"),
        (b"\x00\xff\xfe binary", "not a UTF-8 text file"),
        (b"blades = [", "not valid TOML"),
        (b"hub = 3", "hub must be a table"),
    ],
)
def test_unreadable_files_are_refused(tmp_path, content, fragment):
    path = tmp_path / "bad.toml"
    path.write_bytes(content)
    with pytest.raises(ParameterError, match=fragment):
        PropellerParameters.from_toml(path)


def test_parameters_are_frozen(default_params):
    with pytest.raises(AttributeError):
        default_params.blades = 4  # type: ignore[misc]


def test_a_section_that_folds_over_is_refused():
    with pytest.raises(
        ParameterError, match=r"airfoil.thickness = 0.5 is too thick .* folds over itself"
    ):
        PropellerParameters().with_values(
            {"airfoil.max_camber": 0.0625, "airfoil.camber_position": 0.125}
        )
