"""The design study and the resumed studies refuse what they would ignore (issue 54 item 5):
flags a preset fixes, an empty grid range, a tree whose own design input lies outside the
study's range (named as typed), and a study none of whose cells ran (exit 4, no page and no
sentence from cells that do not exist). The study runs on a 2 x 2 map here (17 cells of a
tree whose t_end is too short: each refused at once), never the 30 x 30 one."""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np
import pytest

from treeimpact.analytic.errors import NotAchieved, ParameterError
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.analytic.model.scenario_toml import scenario_toml
from treeimpact.compare.studies import design as D
from treeimpact.compare.studies import design_words as W



def _main(argv, capsys) -> tuple[int, str]:
    from treeimpact.compare.interface.cli import main

    rc = main(argv)
    err = capsys.readouterr().err.strip()
    return rc, err


def _tree(tmp_path, name, **changes):
    """central-leader with ``changes`` ({"t_end": ..., "impactor.mass": ...}) as a file."""
    scen = load_scenario("central-leader")
    for key, value in changes.items():
        if "." in key:
            section, field = key.split(".")
            part = dataclasses.replace(getattr(scen, section), **{field: value})
            scen = dataclasses.replace(scen, **{section: part})
        else:
            scen = dataclasses.replace(scen, **{key: value})
    path = tmp_path / f"{name}.toml"
    path.write_text(scenario_toml(dataclasses.replace(scen, name=name)))
    return path


@pytest.mark.parametrize("preset", ["design", "default"])
@pytest.mark.parametrize("flag", ["--ladder", "--no-identify"])
def test_a_flag_the_preset_fixes_is_refused(tmp_path, capsys, preset, flag):
    out = tmp_path / "s"
    rc, err = _main(["sweep", "--preset", preset, flag, "--workers", "0", "--out", str(out)],
                    capsys)
    assert rc == 2 and "\n" not in err, err
    assert err.startswith(f"treeimpact: error: {flag}: not used with --preset {preset}")
    assert not out.exists()  # refused before anything ran or was written


@pytest.mark.parametrize("spec", ["a_over_l=0.3:0.3:1", "a_over_l=0.3:0.3:4",
                                  "restitution=0:0:1"])
def test_an_empty_range_is_refused_naming_the_flag_and_value(tmp_path, capsys, spec):
    from treeimpact.compare.studies.sweep.grid import parse_grid

    with pytest.raises(ParameterError) as exc:
        parse_grid([spec])
    msg = str(exc.value)
    # a range START:STOP:COUNT that starts where it stops spans nothing (COUNT 4 would
    # repeat the value); one value is the list NAME=V
    assert msg.startswith(f"--grid {spec!r}: START = STOP") and "empty range" in msg
    name, body = spec.split("=")
    assert f"{name}={body.split(':')[0]}" in msg
    rc, err = _main(["sweep", "--preset", "design", "--grid", spec, "--workers", "0",
                     "--out", str(tmp_path / "d")], capsys)
    assert rc == 2 and "\n" not in err and f"--grid {spec!r}" in err
    assert not (tmp_path / "d").exists()


def test_a_one_value_list_and_a_real_range_are_kept():
    from treeimpact.compare.studies.sweep.grid import parse_grid

    assert parse_grid(["a_over_l=0.3"]).axes[0].values == (0.3,)
    assert parse_grid(["a_over_l=0.2:0.4:3"]).axes[0].values == (0.2, 0.3, 0.4)


def test_a_tree_outside_the_design_range_is_refused_by_its_own_value(tmp_path, capsys):
    from treeimpact.analytic.model.reduction import reduce_trunk

    scen = load_scenario("central-leader")
    mass = 3000.0  # kg: m/M_T = 3000 / 110 = 27, beyond the study's 20
    ratio = mass / reduce_trunk(scen.trunk).dynamic_mass
    assert ratio > D.INPUTS["mass_ratio"].allowed[1]
    path = _tree(tmp_path, "heavy", **{"impactor.mass": mass})
    rc, err = _main(["sweep", "--preset", "design", "--scenario", str(path), "--workers", "0",
                     "--out", str(tmp_path / "d")], capsys)
    assert rc == 2 and "\n" not in err, err
    assert f"--scenario {str(path)!r}" in err and f"m/M_T = {ratio:.4g}" in err
    assert "0.05 to 20" in err  # the allowed range, from the registry
    assert "a_over_l=" not in err and "--grid" not in err  # no grid the user never typed
    assert not (tmp_path / "d").exists()


@pytest.mark.filterwarnings("ignore::treeimpact.analytic.errors.ImplausibleInput")
def test_a_map_no_point_of_which_runs_is_named_by_the_tree(tmp_path):
    """m/M_T = 15.5 is inside the study's range, but at a/l = 0.1 (M_T larger) no impactor
    within the registry's 1e4 kg gives it: the refusal names the tree and its map."""
    from treeimpact.compare.report.validity.design_study import run_design_study

    path = _tree(tmp_path, "h2", **{"impactor.mass": 1700.0})
    with pytest.raises(ParameterError) as exc:
        run_design_study(tmp_path / "d", str(path), count=2, workers=0, progress=False)
    msg = str(exc.value)
    assert msg.startswith(f"--scenario {str(path)!r} (its clamp height a/l x ")
    assert "allowed [0.1, 10000] kg" in msg and "--grid" not in msg


def _short_tree(tmp_path):
    return _tree(tmp_path, "short", t_end=1e-4)  # s: before x_max (about 6 ms)


def test_a_study_none_of_whose_cells_ran_is_not_achieved(tmp_path):
    from treeimpact.compare.report.validity.design_study import run_design_study

    out = tmp_path / "d"
    with pytest.raises(NotAchieved) as exc:
        run_design_study(out, str(_short_tree(tmp_path)), count=2, workers=0, progress=False)
    msg = str(exc.value)
    cells = 3 * 2 * 2 + len(D.DIAMETER_FACTORS)  # three 2 x 2 maps and the diameters
    assert "\n" not in msg and f"({cells} cells: {cells} skipped" in msg
    assert "too short" in msg and "--t-end" not in msg  # the file's t_end, not a flag
    assert not list(out.glob("design.*")) and not list(out.glob("*.png"))


def test_the_command_and_the_api_say_so(tmp_path, capsys, monkeypatch):
    import treeimpact
    from treeimpact.compare.report.validity import design_study, presets

    small = dataclasses.replace(presets.PRESETS["design"], run=functools.partial(
        design_study.run_design_study, count=2))  # the preset on a 2 x 2 map
    monkeypatch.setitem(presets.PRESETS, "design", small)
    path = _short_tree(tmp_path)
    rc, err = _main(["sweep", "--preset", "design", "--scenario", str(path), "--workers", "0",
                     "--out", str(tmp_path / "d")], capsys)
    assert rc == 4 and "\n" not in err and err.startswith("treeimpact: not achieved: design: "
                                                          "no cell of the maps has numbers")
    with pytest.raises(NotAchieved, match="no cell of the maps has numbers"):
        treeimpact.design_map(tmp_path / "e", str(path), count=2, workers=0)
    assert not (tmp_path / "e" / "design.md").exists()


# --------------------------------------------------------------------------- the words


def test_no_sentence_from_a_line_without_cells():
    x = np.array([0.1, 0.35, 0.6])  # a/l
    y = np.array([0.5, 1.2, 3.0])  # m/M_T
    here = {"a_over_l": 0.315, "mass_ratio": 1.2, "contact_duration": 5e-4,
            "restitution": 0.1}
    pair = ("a_over_l", "mass_ratio")
    empty = np.full((3, 3), math.nan)
    text = W.sentence_along(x, y, empty, pair, here, "x_max", 0.05)
    assert text == ("At mass ratio m/M_T = 1.2, no cell along clamp height a/l has a number "
                    "for x_max.")
    nearest = W.sentence_nearest(x, y, {"x_max": empty, "energy_delivered": empty},
                                 {"x_max": 0.05, "energy_delivered": 0.2}, pair, here)
    assert nearest == ("No cell of the clamp height a/l x mass ratio m/M_T map has numbers "
                       "for x_max and energy delivered.")
    # one column without numbers: "at no" speaks of the cells that have them, and says so
    z = np.full((3, 3), 0.5)
    z[:, 2] = math.nan
    text = W.sentence_along(x, y, z, pair, here, "x_max", 0.05)
    assert text.endswith("at no clamp height a/l from 0.1 to 0.35 (1 of its 3 cells have no "
                         "number).")


def test_the_trees_own_cell_without_numbers_is_said_so(tmp_path):
    from treeimpact.compare.report.validity.design_study import tree_cell

    scen = load_scenario(_short_tree(tmp_path))
    cell, problem = tree_cell(scen)
    assert all(math.isnan(v) for v in cell.values()) and "too short" in problem
    here = D.operating_point(scen)
    text = W.sentence_at_point(here, cell, ("x_max",), problem)
    assert "the tree's own cell has no numbers" in text and "off by" not in text
    good, none = tree_cell(load_scenario("central-leader"))
    assert none is None and math.isfinite(good["x_max"])
