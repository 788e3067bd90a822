"""The treeimpact command line: JSON layout, units, and one-line errors with exit code 2."""

import json
import math
import re
import subprocess
import sys

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.metrics import METRIC_KEYS
from treeimpact.compare.interface.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_paper_json_layout(capsys):
    code, out, _ = run(capsys, "paper", "--json")
    assert code == 0
    data = json.loads(out)
    assert set(data["trees"]) == {"open-center", "central-leader"}
    quantities = {"u1", "V", "x0", "T0", "A_x", "M_T", "K_T", "E", "b", "omega_n", "xi",
                  "energy_loss_pct"}
    for tree in data["trees"].values():
        assert set(tree) == quantities
        for row in tree.values():
            assert {"printed", "recomputed", "rel_diff"} <= set(row)
    for d in data["discrepancies"]:
        assert {"equation", "printed", "reproduces_table", "evidence"} == set(d)


def test_simulate_json_layout(capsys):
    code, out, _ = run(capsys, "simulate", "open-center", "--restitution", "0.2", "--t-end",
                       "0.05", "--json")
    assert code == 0
    data = json.loads(out)
    assert set(data["model"]) >= {"M_T", "C_T", "K_T", "m", "k", "restitution", "u1"}
    assert tuple(data["metrics"]) == METRIC_KEYS
    assert data["model"]["restitution"] == 0.2
    assert set(data["scenario"]["trunk"]) >= {"length", "clamp_height", "diameter", "density",
                                              "youngs_modulus", "clamp_mass", "crown_mass",
                                              "damping", "base_stiffness"}
    assert "release_angle_deg" in data["scenario"]["impactor"]
    assert data["scenario"]["contact"]["restitution"] == 0.2


def test_simulate_a_toml_path(capsys, tmp_path):
    f = tmp_path / "billet.toml"
    f.write_text("""
[trunk]
length = 1.0
clamp_height = 0.3
diameter = 0.12
density = 950
youngs_modulus = 9e9
clamp_mass = 0
crown_mass = 0
damping = 0
base_stiffness = inf
[impactor]
type = "billet"
mass = 50
impact_speed = 3.0
[contact]
restitution = 0.2
""")
    code, out, _ = run(capsys, "simulate", str(f), "--json")
    assert code == 0
    data = json.loads(out)
    assert data["metrics"]["theta_b"] is None  # no rebound angle for a billet (JSON null)
    assert data["scenario"]["impactor"]["impact_speed"] == 3.0


@pytest.mark.parametrize("key", ["clamp_mass", "crown_mass", "damping", "base_stiffness"])
def test_a_missing_trunk_key_is_an_error_not_a_silent_zero(capsys, tmp_path, key):
    from pathlib import Path

    text = Path("analytic/model/scenarios/open-center.toml").read_text()
    f = tmp_path / "tree.toml"
    f.write_text("\n".join(l for l in text.splitlines() if not l.startswith(f"{key} =")))
    code, _, err = run(capsys, "simulate", str(f))
    assert code == 2 and err.startswith(f"treeimpact: error: trunk.{key}: missing required value")
    assert err.count("\n") == 1


@pytest.mark.parametrize("argv,field", [
    # the flag as the user typed it (issue 12), with its range
    (["simulate", "open-center", "--restitution", "1.5"],
     "--restitution = 1.5 is out of range: allowed [0, 1]"),
    (["simulate", "open-center", "--restitution", "-0.1"], "--restitution = -0.1"),
    (["simulate", "open-center", "--restitution", "nan"], "--restitution = nan"),
    (["simulate", "open-center", "--t-end", "-1"], "--t-end = -1.0 s"),
    (["simulate", "no-such-tree"], "no-such-tree"),
    (["simulate", "open-center", "--backend", "ode"], "--backend"),
    (["simulate", "open-center", "--segments", "4"], "--segments"),
    (["simulate", "open-center", "--restitution", "abc"], "--restitution"),
    (["frobnicate"], "command"),
])
def test_bad_input_gives_one_line_and_exit_2(capsys, argv, field):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and field in lines[0]
    assert "Traceback" not in err


@pytest.mark.parametrize("body,field", [
    ('[trunk]\nlength = -1\nclamp_height = 0.3\ndiameter = 0.1\ndensity = 900\n'
     'youngs_modulus = 9e9\n[impactor]\nmass = 100\nequivalent_length = 1.5\n'
     'release_angle_deg = 30\n[contact]\nrestitution = 0.1\n', "trunk.length"),
    ("[trunk]\nlength = 1.0\n", "trunk.clamp_height: missing"),
    ("this is not toml ][", "malformed TOML"),
    ('name = "x"\n[trunk]\nlength = 1.0\nclamp_height = 2.0\ndiameter = 0.1\ndensity = 900\n'
     'youngs_modulus = 9e9\n[impactor]\nmass = 100\nequivalent_length = 1.5\n'
     'release_angle_deg = 30\n[contact]\nrestitution = 0.1\n', "trunk.clamp_height"),
    ('[trunk]\nlength = 1.0\nclamp_height = 0.3\ndiameter = 0.1\ndensity = 900\n'
     'youngs_modulus = 9e9\n[impactor]\nmass = -100\nequivalent_length = 1.5\n'
     'release_angle_deg = 30\n[contact]\nrestitution = 0.1\n', "impactor.mass"),
    ('[trunk]\nlength = 1.0\nclamp_height = 0.3\ndiameter = 0.1\ndensity = 900\n'
     'youngs_modulus = "soft"\n[impactor]\nmass = 100\nequivalent_length = 1.5\n'
     'release_angle_deg = 30\n[contact]\nrestitution = 0.1\n', "trunk.youngs_modulus"),
    ('[trunk]\nlength = 1.0\nclamp_height = 0.3\ndiameter = 0.1\ndensity = 900\n'
     'youngs_modulus = 9e9\ncolour = 3\n[impactor]\nmass = 100\nequivalent_length = 1.5\n'
     'release_angle_deg = 30\n[contact]\nrestitution = 0.1\n', "trunk.colour"),
    ('[trunk]\nlength = 1.0\nclamp_height = 0.3\ndiameter = 0.1\ndensity = nan\n'
     'youngs_modulus = 9e9\n[impactor]\nmass = 100\nequivalent_length = 1.5\n'
     'release_angle_deg = 30\n[contact]\nrestitution = 0.1\n', "trunk.density"),
])
def test_malformed_scenario_file_gives_one_line_and_exit_2(capsys, tmp_path, body, field):
    f = tmp_path / "bad.toml"
    f.write_text(body)
    code, out, err = run(capsys, "simulate", str(f))
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and field in err


def test_modes_side_by_side(capsys):
    code, out, _ = run(capsys, "modes", "open-center", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["model"]["static_stiffness"] == pytest.approx(1.2e6, rel=1e-6)
    assert len(data["beam"]["omegas"]) >= 1


def test_console_script_exit_code_without_traceback():
    proc = subprocess.run([sys.executable, "-m", "treeimpact.compare.interface.cli", "simulate",
                           "open-center", "--restitution", "2"], capture_output=True, text=True)
    assert proc.returncode == 2
    assert "Traceback" not in proc.stderr and "--restitution = 2.0" in proc.stderr  # the flag typed


def test_soft_backend_takes_the_engines_contact_stiffness_flag(capsys):
    from treeimpact.compare.interface.cli import main

    assert main(["simulate", "open-center", "--backend", "soft", "--contact-stiffness", "1e9",
                 "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["model"]["contact_stiffness"] == 1e9


def test_simulate_text_shows_the_paper_model_beside_the_backend(capsys):
    """One key per line, units in their own column, and the difference from the analytic
    backend computed from the two backends' own JSON."""
    _, soft_json, _ = run(capsys, "simulate", "central-leader", "--backend", "soft", "--json")
    _, ref_json, _ = run(capsys, "simulate", "central-leader", "--json")
    v, v_ref = json.loads(soft_json)["metrics"]["V"], json.loads(ref_json)["metrics"]["V"]
    code, out, _ = run(capsys, "simulate", "central-leader", "--backend", "soft")
    assert code == 0
    line = next(l for l in out.splitlines() if l.split()[:1] == ["V"])
    assert line.split()[:5] == ["V", f"{v:.6g}", "m/s", f"{v_ref:.6g}",
                                f"{(v - v_ref) / abs(v_ref):+.1%}"]
    assert any(l.split() == ["M_T", "110", "kg"] for l in out.splitlines())
    n_line = next(l for l in out.splitlines() if l.split()[:1] == ["n_impacts"])
    assert n_line.split()[2] == "-"  # a count has no unit, not a "1" read as a number


def test_modes_text_shows_the_difference_from_the_beam(capsys):
    _, js, _ = run(capsys, "modes", "central-leader", "--json")
    res = json.loads(js)
    code, out, _ = run(capsys, "modes", "central-leader")
    assert code == 0
    k, kb = res["model"]["static_stiffness"], res["beam"]["static_stiffness"]
    line = next(l for l in out.splitlines() if "static stiffness at a" in l)
    assert line.split()[-2:] == [f"{(k - kb) / abs(kb):+.1%}", "N/m"]


def test_every_option_has_help_text():
    from treeimpact.compare.interface.cli import build_parser

    parser = build_parser()
    subparsers = next(a for a in parser._actions if a.choices and isinstance(a.choices, dict))
    for name, sub in subparsers.choices.items():
        for action in sub._actions:
            if action.dest != "help":
                assert action.help, f"treeimpact {name} {action.option_strings or action.dest}"


def test_the_command_line_starts_without_scipy():
    """`treeimpact --help` should not pay for scipy (about 0.3 s of its start-up)."""
    code = "import sys, treeimpact.compare.interface.cli; print('scipy' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("command", ["", "paper", "simulate", "modes", "sweep", "report",
                                     "identify", "scenario", "contact"])
def test_every_help_page_prints(command):
    """`treeimpact [COMMAND] --help` exits 0 with its usage (a bare % in a help string makes
    argparse fail while formatting it)."""
    argv = [sys.executable, "-m", "treeimpact.compare.interface.cli",
            *([command] if command else []), "--help"]
    out = subprocess.run(argv, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr[-500:]
    assert out.stdout.startswith("usage: treeimpact")


def test_building_every_help_page_imports_no_scipy():
    """`treeimpact COMMAND --help` builds every subparser: none of them may pull in scipy
    (0.38 s; a module-level scipy import in analytic.records once made --help take 0.55 s)."""
    code = ("import sys; from treeimpact.compare.interface.cli import build_parser; "
            "build_parser(); print('scipy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_simulate_runs_through_the_public_api_and_its_refusal_names_the_flag(monkeypatch,
                                                                             capsys):
    """One face (issue 51 item 3): ``treeimpact simulate`` calls the public API's simulate
    (treeimpact.api re-exports compare.interface.api's; here a spy around it), whose
    refusals name keywords (``t_end``) for a Python caller and the flags (``--t-end``) while
    a command runs (compare.runs.names.NAMING)."""
    import treeimpact.api
    from treeimpact.compare.interface import api

    assert treeimpact.api.simulate is api.simulate
    calls = []
    real = api.simulate

    def spy(*args, **kwargs):
        calls.append((args[1:], kwargs))
        return real(*args, **kwargs)

    monkeypatch.setattr(api, "simulate", spy)
    assert main(["simulate", "open-center", "--backend", "soft", "--restitution", "0.3"]) == 0
    assert calls == [(("soft",), {"restitution": 0.3}), (("analytic",), {"restitution": 0.3})]
    capsys.readouterr()
    assert main(["simulate", "open-center", "--t-end", "0"]) == 2
    assert "--t-end = 0.0 s is out of range" in capsys.readouterr().err
    with pytest.raises(api.ParameterError, match=r"^t_end = 0 s is out of range"):
        real("open-center", t_end=0)


@pytest.mark.parametrize("backend", ["analytic", "beam", "mujoco"])
def test_modes_writes_the_public_apis_result(capsys, backend):
    """``treeimpact modes --json`` is treeimpact.modes' typed result as JSON (Modes.to_json,
    issue 51 item 3): the same numbers the API returns, a chain's segments with it."""
    import treeimpact as ti

    assert main(["modes", "central-leader", "--backend", backend, "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    want = ti.modes("central-leader", backend)
    assert got["model"]["static_stiffness"] == want.model.static_stiffness
    assert got["model"]["omegas"] == list(want.model.omegas)
    assert got["beam"]["omegas"] == list(want.beam.omegas)
    assert got["model"].get("segments") == want.model.segments


def _spied(monkeypatch, name, module="api"):
    """A spy around the API function ``name`` of compare.interface.``module`` (``api``,
    ``api_records`` or ``api_studies``: the function treeimpact.api re-exports, which the
    command calls): the calls it saw, (args, kwargs) each."""
    import importlib

    import treeimpact.api

    api = importlib.import_module(f"treeimpact.compare.interface.{module}")
    assert getattr(treeimpact.api, name) is getattr(api, name)
    calls, real = [], getattr(api, name)

    def spy(*args, **kwargs):
        calls.append((args, kwargs))
        return real(*args, **kwargs)

    monkeypatch.setattr(api, name, spy)
    return calls, real


def test_paper_prints_the_public_apis_result(monkeypatch, capsys):
    """One face (issue 51 item 3): ``treeimpact paper --json`` is treeimpact.paper()'s result
    with the provenance added, the numbers parsed (not compared as text)."""
    calls, real = _spied(monkeypatch, "paper")
    code, out, _ = run(capsys, "paper", "--json")
    assert code == 0 and calls == [((), {"fit_contact": False})]
    printed = json.loads(out)
    printed.pop("provenance")
    assert printed == json.loads(json.dumps(real(), default=float))


def test_contact_prints_the_public_apis_result_and_its_refusal_names_the_flag(monkeypatch,
                                                                              capsys):
    """``treeimpact contact --json`` is treeimpact.contact_settings()'s result for the flags
    (its engines --engine's); a refusal names the flag while the command runs and the
    keyword for a Python caller; an engine without contact settings is refused by name."""
    calls, real = _spied(monkeypatch, "contact_settings")
    argv = ["--mass", "132.4", "--other-mass", "4", "--restitution", "0.5",
            "--touch-duration", "2e-3", "--dt", "4e-5", "--engine", "mujoco"]
    code, out, _ = run(capsys, "contact", *argv, "--json")
    assert code == 0 and calls[0][1]["engines"] == ("mujoco",)
    got = real(mass=132.4, other_mass=4.0, restitution=0.5, touch_duration=2e-3, dt=4e-5,
               engines=("mujoco",))
    assert json.loads(out) == json.loads(json.dumps(got, default=float))
    assert main(["contact", *argv[:4], "--restitution", "1.5", *argv[6:]]) == 2
    assert "--restitution" in capsys.readouterr().err
    with pytest.raises(ParameterError, match=r"^restitution"):
        real(mass=132.4, restitution=1.5, touch_duration=2e-3, dt=4e-5)
    with pytest.raises(ParameterError, match=r"^engines: 'analytic' gives no contact"):
        real(mass=132.4, restitution=0.5, touch_duration=2e-3, dt=4e-5,
             engines=("analytic",))


#: The pendulum test of central-leader (its scenario file) as identify's flags.
CENTRAL_LEADER_TEST = ["--impactor-mass", "132.4", "--equivalent-length", "1.51",
                    "--release-angle-deg", "36.39", "--clamp-height", "0.315",
                    "--diameter", "0.126"]


def test_identify_prints_the_public_apis_identification(monkeypatch, capsys, tmp_path):
    """``treeimpact identify --json`` is treeimpact.identify()'s Identification: its fit's
    quantities and the paper's procedure's readings (``procedure``) of the record it read,
    and the figure it draws; the numbers parsed, not compared as text."""
    import treeimpact as ti

    record = tmp_path / "rec.csv"
    assert main(["simulate", "central-leader", "--record", str(record), "--noise", "0.01"]) == 0
    capsys.readouterr()
    calls, real = _spied(monkeypatch, "identify", "api_records")
    code, out, _ = run(capsys, "identify", str(record), *CENTRAL_LEADER_TEST, "--json",
                       "--plot", str(tmp_path / "fit.png"))
    assert code == 0 and len(calls) == 1 and calls[0][1]["plot"] == str(tmp_path / "fit.png")
    assert (tmp_path / "fit.png").read_bytes()[:4] == b"\x89PNG"
    printed = json.loads(out)
    ident = real(str(record), ti.load_scenario("central-leader"))
    assert printed["paper"] == json.loads(json.dumps(ident.procedure, default=float))
    for name in ("M_T", "K_T", "C_T", "restitution"):
        want = getattr(ident, name).value  # not fixed by the record: NaN, null in JSON
        assert printed["fit"][name]["value"] == (None if math.isnan(want) else want)
    # the paper's C_T is 2 b (M_T + m) of its b (eq 34), its trunk ratio C_T / (2 sqrt(K M))
    paper = ident.procedure["paper"]
    assert paper["trunk_damping_ratio"] == pytest.approx(  # rounding only: one formula each
        paper["C_T"] / (2 * math.sqrt(paper["K_T"] * paper["M_T"])), rel=1e-12)


@pytest.mark.parametrize("flags, typed, keyword, value", [
    (["--restitution", "1.5"], "--restitution = 1.5", "restitution = 1.5",
     {"restitution": 1.5}),
    (["--clamp-height", "-0.3"], "--clamp-height = -0.3", "clamp_height = -0.3",
     {"clamp_height": -0.3}),
    (["--plot", "fit.txt"], "--plot 'fit.txt': allowed a file ending in", "plot 'fit.txt'",
     {"plot": "fit.txt"})])
def test_identifys_refusal_is_the_apis_naming_the_flag_or_the_keyword(
        capsys, tmp_path, flags, typed, keyword, value):
    """identify's inputs are checked once, by the API (the registry's range; the figure's
    formats), before the record is read: one line naming the flag as typed in the command
    (exit 2), the keyword for a Python caller."""
    import treeimpact as ti

    record = tmp_path / "missing.csv"  # never read: the check comes first
    argv = list(CENTRAL_LEADER_TEST)
    for flag, text in zip(flags[::2], flags[1::2]):
        if flag in argv:
            argv[argv.index(flag) + 1] = text
        else:
            argv += [flag, text]
    assert main(["identify", str(record), *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"treeimpact: error: {typed}") and err.count("\n") == 1, err
    given = {"clamp_height": 0.315, "diameter": 0.126, **value}
    with pytest.raises(ParameterError, match=f"^{re.escape(keyword)}"):
        ti.identify(record, ti.load_scenario("central-leader").impactor, **given)


def test_a_study_that_is_not_a_directory_is_refused_once_by_its_name(tmp_path, capsys):
    """``--study`` is checked once, in the API's report, before any run: the command's
    refusal names the flag (exit 2), a Python caller's the keyword ``studies``."""
    import treeimpact as ti

    missing = str(tmp_path / "no-study")
    assert main(["report", "--out", str(tmp_path / "out"), "--study", missing]) == 2
    assert f"--study {missing!r}: not a directory" in capsys.readouterr().err
    with pytest.raises(ParameterError, match=rf"^studies {re.escape(repr(missing))}: not a"):
        ti.report(tmp_path / "out", studies=(missing,))
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


#: The columns of a sweep's table that a second run of the same sweep changes too (its
#: timings, when and by which task a row finished).
VOLATILE = ("wall_s", "finished", "task", "worker")


def _rows(table):
    """A sweep's table without its volatile columns, in one row order."""
    kept = table.drop(columns=[c for c in VOLATILE if c in table.columns])
    return kept.sort_values(["point", "target"]).reset_index(drop=True)


def test_sweep_calls_the_public_api_and_its_table_is_the_apis(tmp_path, monkeypatch, capsys):
    """One face (issue 51 item 3): ``treeimpact sweep`` is treeimpact.sweep() then
    treeimpact.sweep_pages() (a spy sees each call, with the flags as keywords), its table
    the one a Python caller's sweep of the same grid gives, cell for cell."""
    import pandas as pd

    import treeimpact as ti
    from treeimpact.compare.studies.sweep.journal import read_table

    calls, _ = _spied(monkeypatch, "sweep", "api_studies")
    pages, _ = _spied(monkeypatch, "sweep_pages", "api_studies")
    grid = ["restitution=0.1:0.5:3"]
    code, out, _ = run(capsys, "sweep", "--grid", grid[0], "--backend", "analytic",
                       "--workers", "0", "--tolerance", "0.1", "--out", str(tmp_path / "cli"))
    assert code == 0 and out.startswith("sweep: 3 rows (ok 3); 3 written now, 0 done before")
    assert calls[0][0] == (grid, str(tmp_path / "cli"))
    assert {k: calls[0][1][k] for k in ("backends", "workers", "identify", "progress")} == {
        "backends": ["analytic"], "workers": 0, "identify": True, "progress": None}
    assert len(pages) == 1 and pages[0][1] == {"tolerance": 0.1}
    assert f"md: {tmp_path / 'cli' / 'study.md'}" in out.splitlines()
    api = ti.sweep(grid, tmp_path / "api", backends=("analytic",), workers=0)
    # the same code on the same inputs: the numbers bit for bit, not within a tolerance
    pd.testing.assert_frame_equal(_rows(api.table), _rows(read_table(tmp_path / "cli")),
                                  check_exact=True)


def test_a_sweep_refusal_names_the_flag_in_the_command_and_the_keyword_in_python(tmp_path,
                                                                                 capsys):
    """An unknown backend is checked once, where it enters the API's sweep: the command's
    refusal names --backend (exit 2, one line), a Python caller's the keyword backends;
    nothing is written either way."""
    import treeimpact as ti

    out = tmp_path / "s"
    code, _, err = run(capsys, "sweep", "--grid", "restitution=0.1", "--backend",
                       "analytic,nosuch", "--out", str(out))
    assert code == 2 and err.strip() == ("treeimpact: error: --backend 'nosuch': allowed "
                                         "analytic, soft, beam, mujoco, bullet "
                                         "(comma-separated)")
    with pytest.raises(ParameterError, match=r"^backends 'nosuch': allowed analytic"):
        ti.sweep(["restitution=0.1"], out, backends=("analytic", "nosuch"))
    with pytest.raises(ParameterError, match=r"^grid 'nosuch=1': unknown name"):
        ti.sweep(["nosuch=1"], out, backends=("analytic",))
    assert not out.exists()


@pytest.mark.parametrize("spec, given, why", [
    ("soft.foo=1", {"soft": {"foo": 1}}, "backend 'soft' has no option 'foo'; allowed: "),
    ("mujoco.dt=-1", {"mujoco": {"dt": -1}}, "dt = -1"),
    ("nosuch.dt=1", {"nosuch": {"dt": 1}}, "backend 'nosuch': allowed analytic"),
])
def test_a_sweeps_fixed_option_is_checked_once_by_the_api(tmp_path, capsys, spec, given, why):
    """A fixed option is checked once, where it enters the API's sweep, whether the
    command's --option spec or a Python caller's {backend: {name: value}}: refused before
    any run (not a sweep of skipped rows), naming --option in the command and options in
    Python with the entry as a spec; nothing is written."""
    import treeimpact as ti

    out = tmp_path / "s"
    code, _, err = run(capsys, "sweep", "--grid", "restitution=0.1", "--backend",
                       "analytic,soft", "--option", spec, "--out", str(out))
    assert code == 2 and err.startswith(f"treeimpact: error: --option {spec!r}: {why}"), err
    with pytest.raises(ParameterError, match=rf"^options {re.escape(repr(spec))}: "
                                             rf"{re.escape(why)}"):
        ti.sweep(["restitution=0.1"], out, backends=("analytic", "soft"), options=given)
    assert not out.exists()


@pytest.mark.parametrize("flags, keyword, given", [
    (["--tolerance", "0.1"], "tolerance", {"tolerance": 0.1}),
    (["--backend", "analytic"], "backends", {"backends": ("analytic",)}),
    (["--sensitivity-scenario", "open-center"], "sensitivity_scenarios",
     {"sensitivity_scenarios": ["open-center"]}),
])
def test_sweep_preset_calls_the_apis_study_whose_refusal_names_flag_or_keyword(
        tmp_path, monkeypatch, capsys, flags, keyword, given):
    """``treeimpact sweep --preset`` is treeimpact.study() (a spy sees the call): what the
    design study fixes is refused there, once, before anything is written, naming the flag
    while the command runs and the keyword for a Python caller."""
    import treeimpact as ti

    calls, _ = _spied(monkeypatch, "study", "api_studies")
    out = tmp_path / "d"
    code, _, err = run(capsys, "sweep", "--preset", "design", *flags, "--workers", "0",
                       "--out", str(out))
    err = err.strip()
    assert code == 2 and "\n" not in err
    assert err.startswith(f"treeimpact: error: {flags[0]}: not used with --preset design")
    assert calls[0][0] == (str(out), "design") and calls[0][1]["workers"] == 0
    untyped = calls[0][1]["backends"] is None  # --backend not typed: the preset's own
    assert untyped == (keyword != "backends")
    with pytest.raises(ParameterError, match=rf"^{keyword}: not used with preset design"):
        ti.study(out, "design", workers=0, **given)
    with pytest.raises(ParameterError, match=r"^backends 'nosuch': allowed"):
        ti.study(out, "default", backends=("nosuch",))
    assert not out.exists()
