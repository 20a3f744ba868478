"""The gallery: every example design builds to one valid solid; its note is there."""

import pytest
from conftest import EXAMPLES_DIR as EXAMPLES
from conftest import SHIPPED_DESIGNS

from torus_cad.kernel.checks import single_valid_solid
from torus_cad.parameters import PropellerParameters
from torus_cad.propeller import build_propeller

#: The workshop examples have their own tests.
GALLERY = [path.name for path in SHIPPED_DESIGNS if not path.match("workshop_*.toml")]


def test_the_gallery_has_the_designs_the_issue_asks_for():
    assert {
        "multirotor_5in_3blade.toml",
        "multirotor_5in_3blade_ccw.toml",
        "prop_10x5_2blade.toml",
        "marine_3blade_loop.toml",
        "cooling_fan_7blade.toml",
        "spec_default.toml",
    } <= set(GALLERY)


def test_the_multirotor_pair_is_a_cw_ccw_pair_with_a_5_mm_bore():
    cw = PropellerParameters.from_toml(EXAMPLES / "multirotor_5in_3blade.toml")
    ccw = PropellerParameters.from_toml(EXAMPLES / "multirotor_5in_3blade_ccw.toml")
    assert (cw.handedness.value, ccw.handedness.value) == ("cw", "ccw")
    assert cw.hub.bore_diameter == ccw.hub.bore_diameter == 5.0
    # the same design otherwise
    assert cw.with_values({"name": ccw.name, "handedness": "ccw"}) == ccw


@pytest.mark.parametrize("name", GALLERY)
def test_every_example_has_a_note_and_reads(name):
    text = (EXAMPLES / name).read_text()
    note = [line for line in text.splitlines()[:20] if line.startswith("#")]
    assert len(note) >= 3, f"{name} needs a comment block saying what the design is for"
    PropellerParameters.from_toml(EXAMPLES / name)  # reads (airfoil files relative to examples/)


@pytest.mark.parametrize("name", GALLERY)
def test_every_example_builds_one_valid_solid(name):
    propeller = build_propeller(EXAMPLES / name)
    solid = single_valid_solid(propeller.solid, name)
    assert len(solid.Solids()) == 1 and solid.isValid()
    assert len(propeller.solid.Shells()) == 1
