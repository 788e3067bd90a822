"""load_scenario parses each file's content once (a sweep loads the same file for every
run): what it returns must still be the file as it is now, and the caller's own."""

from __future__ import annotations

import pytest
from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.scenario_toml import scenario_toml


def test_a_caller_s_notes_are_its_own():
    """Two loads of one shipped tree: equal, but a change to one's notes is not the other's."""
    a, b = load_scenario("central-leader"), load_scenario("central-leader")
    assert a == b and a.notes == b.notes
    a.notes["given"] = "changed by a caller"
    assert load_scenario("central-leader").notes == b.notes != a.notes


def test_a_file_changed_between_loads_is_read_again(tmp_path):
    """The cache is keyed by the file's bytes: an edited file gives the edited scenario, and a
    file made bad gives its error every time (errors are not cached as results)."""
    path = tmp_path / "t.toml"
    text = scenario_toml(load_scenario("open-center"))
    path.write_text(text)
    assert load_scenario(path).contact.restitution == load_scenario("open-center").contact.restitution
    path.write_text(text.replace("restitution = ", "restitution = 0.25 #", 1))
    assert load_scenario(path).contact.restitution == 0.25
    path.write_text(text.replace("[trunk]", "[trunk", 1))
    for _ in range(2):
        with pytest.raises(ParameterError, match="malformed TOML"):
            load_scenario(path)
