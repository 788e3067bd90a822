"""Every number carries where it came from (issue 25 item 4): code version, engine and
library versions, the scenario's digest and the run's numerical settings."""

from __future__ import annotations

import json
from dataclasses import replace
from importlib import metadata

from treeimpact.analytic.model.parameters import Contact
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.interface.cli import main
from treeimpact.compare.runs.provenance import provenance, scenario_digest


def _json(capsys, *argv):
    assert main(list(argv)) == 0
    return json.loads(capsys.readouterr().out)


def test_simulate_json_names_the_code_engines_scenario_and_settings(capsys):
    out = _json(capsys, "simulate", "open-center", "--backend", "beam", "--elements", "6",
                "--json")
    p = out["provenance"]
    assert p["code"]["treeimpact"] == metadata.version("treeimpact")
    assert p["environment"]["numpy"] == metadata.version("numpy")
    assert p["scenario"] == {"name": "open-center",
                             "sha1": scenario_digest(load_scenario("open-center"))}
    assert p["run"]["backend"] == "beam" and p["run"]["elements"] == 6
    assert p["options"] == {"elements": 6}


def test_the_digest_follows_every_input():
    """One changed input, another digest; the same inputs, the same digest."""
    scen = load_scenario("open-center")
    assert scenario_digest(scen) == scenario_digest(load_scenario("open-center"))
    other = replace(scen, contact=Contact(restitution=0.2, duration=scen.contact.duration))
    assert scenario_digest(other) != scenario_digest(scen)


def test_modes_and_paper_json_carry_it(capsys):
    modes = _json(capsys, "modes", "central-leader", "--json")
    assert modes["provenance"]["scenario"]["name"] == "central-leader"
    paper = _json(capsys, "paper", "--json")
    assert set(paper["provenance"]) >= {"code", "environment"}


def test_a_checkout_names_its_commit():
    """Run from this repository's checkout: the commit is the 40-hex HEAD."""
    code = provenance()["code"]
    assert code["git_commit"] is None or len(code["git_commit"]) == 40
