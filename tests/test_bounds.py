"""The per-tree bound mechanism (compare.bounds): an entry naming a bound gets that tree's
tolerance and words; a bound that is not registered, or given beside a fixed rel, is
refused in one line."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare import bounds as B


def _pair(value, reference):
    run = lambda v: SimpleNamespace(values={"x_max": v}, result=None)  # noqa: E731
    return B.Pair(None, None, "x_max", run(value), run(reference))


def test_a_named_bound_sets_the_tree_s_tolerance_and_says_how():
    name = "test-half-the-reference"
    B.BOUNDS.pop(name, None)
    B.register(name)(lambda p: B.Bound(0.5 * p.reference_value, "half of it"))
    try:
        entry = B.tree_entry({"bound": name, "reason": "because"}, _pair(1.0, 0.02))
    finally:
        B.BOUNDS.pop(name)
    assert math.isclose(entry["rel"], 0.01) and entry["reason"] == "because: half of it"


def test_an_entry_without_a_bound_is_unchanged():
    entry = {"rel": 0.005, "reason": "r"}
    assert B.tree_entry(entry, _pair(1.0, 1.0)) is entry and B.tree_entry(None, None) is None


@pytest.mark.parametrize("entry, words", [
    ({"bound": "no-such-bound", "reason": "r"}, "bound = 'no-such-bound': allowed"),
    ({"bound": next(iter(B.BOUNDS), "x"), "rel": 0.1, "reason": "r"}, "not both")])
def test_a_bad_bound_is_refused_in_one_line(entry, words):
    if entry["bound"] not in B.BOUNDS and "rel" in entry:
        pytest.skip("no bound registered yet")
    with pytest.raises(ParameterError, match=words):
        B.validate_bound("step.x.x_max", entry)


def test_a_bound_that_is_not_a_number_is_an_error():
    name = "test-nan"
    B.BOUNDS.pop(name, None)
    B.register(name)(lambda p: B.Bound(math.nan, "?"))
    try:
        with pytest.raises(ValueError, match="rel = nan"):
            B.tree_entry({"bound": name, "reason": "r"}, _pair(1.0, 1.0))
    finally:
        B.BOUNDS.pop(name)


@pytest.mark.parametrize("tree, shown", [("central-leader", True), ("a user's edit", False)])
def test_the_shipped_trees_measurements_are_quoted_on_a_shipped_tree_only(tree, shown):
    """An entry's ``measured`` (the shipped trees' numbers) joins its reason on a shipped
    tree, input for input; on any other tree (here central-leader with one input changed)
    the reason is the physics alone."""
    import dataclasses

    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.compare.ladder import Ladder

    scen = load_scenario("central-leader")
    if not shown:
        scen = dataclasses.replace(scen, t_end=0.05)
    ladder = Ladder(scen, [], {}, {})
    entry = ladder._shown({"rel": 0.01, "reason": "physics", "measured": "0.3 % measured"})
    assert entry["reason"] == ("physics (0.3 % measured)" if shown else "physics")
