"""Where M_T comes from (eq 7; issue 50 item 6's first-screen line): the three parts of
analytic.model.reduction.mass_parts against the paper's printed closed form for a rigid
clamp, and the report's one line read from them."""

from __future__ import annotations

import dataclasses
import math
import re

import pytest

from treeimpact.analytic.model.reduction import mass_parts, printed_dynamic_mass, reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario, shipped_scenarios
from treeimpact.compare.report import mass_origin


@pytest.mark.parametrize("name", shipped_scenarios())
def test_the_parts_are_eq7_and_the_printed_form_for_a_rigid_clamp(name):
    """With the root rigid (k_theta = inf) the static shape is the printed one: the crown
    counts ((3 l - a) / (2 a))^2 times and the whole is the printed M_T after eq 7 (an
    independent closed form); with the shipped root spring the parts still sum to
    reduce_trunk's M_T, bit for bit (one sum)."""
    trunk = load_scenario(name).trunk
    assert mass_parts(trunk).total == reduce_trunk(trunk).dynamic_mass
    rigid = dataclasses.replace(trunk, base_stiffness=math.inf)
    parts = mass_parts(rigid)
    a, l = rigid.clamp_height, rigid.length
    assert parts.crown_weight == pytest.approx(((3 * l - a) / (2 * a)) ** 2, rel=1e-12)
    assert parts.total == pytest.approx(printed_dynamic_mass(rigid), rel=1e-12)  # round-off
    assert parts.clamp == rigid.clamp_mass


def test_the_first_screen_line_reads_the_parts():
    """The line's numbers are the parts at 3 digits, and they add up to its M_T."""
    trunk = load_scenario("realistic-crown").trunk
    parts = mass_parts(trunk)
    text = mass_origin(trunk)
    numbers = [float(v) for v in re.findall(r"\d+(?:\.\d+)?", text)]
    total, wood, clamp, crown, given, weight, motion = numbers[:7]
    assert total == pytest.approx(parts.total, rel=5e-3)  # 3 significant digits
    assert (wood, clamp, crown) == pytest.approx((parts.trunk, parts.clamp, parts.crown),
                                                 rel=5e-3)
    assert given == trunk.crown_mass and weight == pytest.approx(parts.crown_weight, rel=5e-3)
    assert motion == pytest.approx(math.sqrt(parts.crown_weight), rel=5e-3)
