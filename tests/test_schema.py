"""The schema machinery: a parameter declared once is validated, documented, fuzzed and tabulated.

A made-up table with one new numeric parameter stands in for the next issue's parameters: the
one declaration is all it takes for every derived view to know it.
"""

from __future__ import annotations

import pytest
from pydantic import Field

from torus_cad.errors import ParameterError
from torus_cad.parameters import PropellerParameters, parameter_specs
from torus_cad.parameters.document import Document
from torus_cad.parameters.parameter_reference import markdown_table
from torus_cad.parameters.schema import Section, iter_parameter_specs, param


class Mounting(Section):
    """A made-up table."""

    bore_diameter: float = param(
        0.0, unit="mm", ge=0.0, le=50.0, fuzz=(0.0, 8.0), doc="coaxial through-bore"
    )


class Extended(Document):
    """A design document with one table more."""

    blades: int = param(3, ge=1, le=12, doc="number of blades")
    mounting: Mounting = Field(default_factory=Mounting)


def test_one_declaration_gives_validation_with_field_value_and_range():
    assert Extended().with_values({"mounting.bore_diameter": 5.0}).mounting.bore_diameter == 5.0
    with pytest.raises(
        ParameterError, match=r"^mounting.bore_diameter = 60 is out of range; allowed \[0, 50\] mm$"
    ):
        Extended().with_values({"mounting.bore_diameter": 60.0})


def test_one_declaration_gives_the_commented_toml_and_its_round_trip(tmp_path):
    text = Extended().to_toml()
    assert "bore_diameter = 0.0" in text and "coaxial through-bore (mm); [0, 50]" in text
    path = tmp_path / "extended.toml"
    path.write_text(text)
    assert Extended.from_toml(path) == Extended()


def test_one_declaration_gives_a_reference_row_and_fuzz_range():
    assert (
        "| `mounting.bore_diameter` | `0` | mm | [0, 50] | coaxial through-bore |"
        in markdown_table(Extended)
    )
    spec = next(
        spec for spec in iter_parameter_specs(Extended) if spec.key == "mounting.bore_diameter"
    )
    assert (spec.fuzz.low, spec.fuzz.high) == (0.0, 8.0) and spec.section == "mounting"


def test_unknown_keys_suggest_the_closest_in_any_table():
    with pytest.raises(
        ParameterError,
        match=r"unknown key 'mounting.bore_diamter'; did you mean 'mounting.bore_diameter'\?",
    ):
        Extended().with_values({"mounting.bore_diamter": 1.0})


@pytest.mark.parametrize(
    "changes, message",
    [
        ({"blades": 10**401}, r"^blades = a huge number is out of range; allowed \[1, 12\]$"),
        ({"blades": 10**5001}, r"^blades = a huge number is out of range; allowed \[1, 12\]$"),
        ({"hub.radius": 10**401}, r"^hub.radius "),
        ({"name": "abc\n"}, r"^name = 'abc\\n' must be 1-64 letters"),
        (
            {"centerline.frame": "bishop"},
            r"^centerline.frame = 'bishop' is not allowed; "
            r"choose one of frenet, rotation_minimizing$",
        ),
    ],
)
def test_hostile_values_are_one_line_parameter_errors(changes, message):
    with pytest.raises(ParameterError, match=message) as raised:
        PropellerParameters().with_values(changes)
    assert "\n" not in str(raised.value).replace("\\n", "")


def test_every_numeric_parameter_declares_a_range_unit_and_doc():
    for spec in parameter_specs():
        assert spec.doc, spec.key
        if spec.kind in (int, float):
            assert spec.bounds.low is not None and spec.bounds.high is not None, spec.key


def test_a_utf8_bom_file_is_accepted(tmp_path):
    path = tmp_path / "windows.toml"
    path.write_bytes("\ufeffblades = 4\n".encode())
    assert PropellerParameters.from_toml(path).blades == 4


@pytest.mark.parametrize("special", ["/dev/zero", "fifo", "folder"])
def test_only_regular_files_are_read_as_configuration(tmp_path, special):
    import os

    if special == "fifo":
        path = tmp_path / "pipe.toml"
        os.mkfifo(path)
    elif special == "folder":
        path = tmp_path
    else:
        path = special
    with pytest.raises(ParameterError, match="is not a regular file"):
        PropellerParameters.from_toml(path)


class Undocumented(Section):
    spacer_length: float = param(
        1.0, unit="mm", ge=0.0, le=20.0, doc="spacer between hub and mount"
    )


class WithUndocumentedTable(Document):
    """A design document whose extra table has no docstring."""

    spacer: Undocumented = Field(default_factory=Undocumented)


def test_a_table_without_docstring_has_an_empty_description_and_still_writes_toml():
    from torus_cad.parameters.schema import section_docs

    assert section_docs(WithUndocumentedTable) == {"spacer": ""}
    text = WithUndocumentedTable().to_toml()
    assert "\n[spacer]\n" in text and "spacer between hub and mount (mm); [0, 20]" in text
    assert (
        WithUndocumentedTable.from_dict(WithUndocumentedTable().to_dict()).spacer.spacer_length
        == 1.0
    )
