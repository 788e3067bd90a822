"""Tests of compare.studies.sweep: grid specs, scenario overrides, the sweep runner (resume,
failures, Dask), discrepancy and identification maps, speed points, and ``treeimpact sweep``.

Runs use the analytic backend (4 ms each) and a few soft-contact runs (0.1 s each) so the
file stays within a few seconds on a busy 2-core machine.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from treeimpact.analytic.continuum.chain import SEGMENTS
from treeimpact.analytic.errors import ParameterError, SimulationDiverged
from treeimpact.analytic.impact.simulate import simulate
from treeimpact.analytic.metrics import METRIC_KEYS
from treeimpact.analytic.model.options import RESTITUTION, T_END, Option
from treeimpact.analytic.model.reduction import reduce_trunk
from treeimpact.analytic.model.scenario import load_scenario
from treeimpact.compare.runs.cache import INVALID
from treeimpact.compare.studies.speed import speed_points
from treeimpact.compare.studies.sweep.apply import apply_point
from treeimpact.compare.studies.sweep.grid import derived_ratios, parse_axis, parse_grid
from treeimpact.compare.studies.sweep.journal import JOURNAL, TABLE, read_table
from treeimpact.compare.studies.sweep.maps import (
    discrepancies,
    identification_maps,
    validity_maps,
)
from treeimpact.compare.studies.sweep.run import run_sweep

# --------------------------------------------------------------------------- grid specs


def test_range_spec_has_count_values_with_both_ends():
    ax = parse_axis("restitution=0:0.9:10")
    assert ax.values == pytest.approx([0.1 * i for i in range(10)], abs=1e-15)
    assert ax.values[0] == 0.0 and ax.values[-1] == 0.9
    assert ax.parameter.target == "contact.restitution"


def test_list_spec_of_segments_is_integers_for_the_engine_option():
    ax = parse_axis("segments=1,2,4")
    assert ax.values == (1, 2, 4) and all(type(v) is int for v in ax.values)
    assert (ax.parameter.kind, ax.parameter.target) == ("option", "segments")


def test_grid_points_are_the_cartesian_product_first_axis_slowest():
    g = parse_grid(["restitution=0.1,0.2", "crown_ratio=0:4:3"])
    assert len(g) == 6
    assert g.points()[:3] == [{"restitution": 0.1, "crown_ratio": c} for c in (0.0, 2.0, 4.0)]


@pytest.mark.parametrize("spec", [
    "restitution", "restitution=", "restitution=0:1", "restitution=0:1:2:3",
    "restitution=a:1:3", "restitution=0:1:0", "restitution=0:1:2.5", "restitution=0:1:1",
    "restitution=0.1,,0.2", "restitution=0.1,nan", "restitution=1,1", "segments=1.5,2",
    "foo=1", "trunk.bark=1", "pendulum.mass=1", "restitution=low,high", "a b=1",
])
def test_bad_grid_spec_is_one_line_naming_the_flag_and_the_form(spec):
    with pytest.raises(ParameterError) as exc:
        parse_axis(spec)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith(f"--grid {spec!r}")
    assert "NAME=START:STOP:COUNT" in msg or "allowed" in msg


def test_same_parameter_twice_or_with_its_ratio_is_refused():
    with pytest.raises(ParameterError, match="same parameter"):
        parse_grid(["restitution=0.1", "contact.restitution=0.2"])
    with pytest.raises(ParameterError, match="ratio"):
        parse_grid(["trunk.crown_mass=1", "crown_ratio=0.5"])


def test_option_words_are_kept_for_engine_options_only():
    assert parse_axis("option.contact=soft,newton").values == ("soft", "newton")


# --------------------------------------------------------------------------- overrides


def test_dotted_names_and_aliases_rebuild_the_scenario():
    s = load_scenario("central-leader")
    scen, opts = apply_point(s, {"restitution": 0.4, "trunk.crown_mass": 7.5, "segments": 8,
                                 "dt": 1e-5, "impactor.release_angle_deg": 20.0})
    assert scen.contact.restitution == 0.4
    assert scen.trunk.crown_mass == 7.5
    assert scen.impactor.release_angle_rad == pytest.approx(math.pi / 9, rel=1e-15)
    assert opts == {"segments": 8, "dt": 1e-5}
    assert s.contact.restitution == 0.1  # the base scenario is untouched (frozen)


def test_contact_stiffness_replaces_the_duration():
    s = load_scenario("central-leader")
    assert s.contact.duration == 5e-4
    scen, _ = apply_point(s, {"contact_stiffness": 2e9})
    assert (scen.contact.stiffness, scen.contact.duration) == (2e9, None)


@pytest.mark.parametrize("ratios", [
    {"mass_ratio": 0.5}, {"a_over_l": 0.25}, {"crown_ratio": 3.0},
    {"mass_ratio": 2.0, "a_over_l": 0.5, "crown_ratio": 1.5},
])
def test_derived_ratios_round_trip(ratios):
    s = load_scenario("open-center")
    scen, _ = apply_point(s, ratios)
    got = derived_ratios(scen)
    for k, v in ratios.items():
        assert got[k] == pytest.approx(v, rel=1e-12)  # round-off of one product and quotient
    t = scen.trunk
    # independent of compare.studies.sweep: m_trunk = rho pi d^2 / 4 l, M_T from eq 7
    # (reduce_trunk)
    if "crown_ratio" in ratios:
        m_trunk = t.density * math.pi * t.diameter ** 2 / 4 * t.length
        assert t.crown_mass == pytest.approx(ratios["crown_ratio"] * m_trunk, rel=1e-12)
    if "a_over_l" in ratios:
        assert t.clamp_height == pytest.approx(ratios["a_over_l"] * s.trunk.length, rel=1e-12)
    if "mass_ratio" in ratios:
        assert scen.impactor.mass == pytest.approx(
            ratios["mass_ratio"] * reduce_trunk(t).dynamic_mass, rel=1e-12)


def test_point_outside_a_range_names_the_grid_parameter():
    with pytest.raises(ParameterError, match=r"^crown_ratio = -1.*trunk.crown_mass"):
        apply_point(load_scenario("central-leader"), {"crown_ratio": -1.0})


# --------------------------------------------------------------------------- the runner


#: The stand-in engines' options tables (compare.runs.backends reads a backend's options there).
FAKE_OPTIONS = {"restitution": RESTITUTION, "t_end": T_END}
T_END_OPTIONS = {"t_end": T_END}
TRUNK_OPTIONS = {"trunk": Option(("sdof", "chain"), "trunk"), "segments": SEGMENTS,
                 "pendulum": Option(("linear", "full"), "pendulum"), "t_end": T_END}
SEGMENTS_OPTIONS = {"segments": SEGMENTS, "t_end": T_END}


def _explode_or_diverge(scenario):
    """A stand-in engine: fails at e >= 0.8, diverges at e = 0.5, else the analytic run."""
    e = scenario.contact.restitution
    if e >= 0.8:
        raise RuntimeError("solver blew up")
    if e == 0.5:
        raise SimulationDiverged("energy grew")
    return simulate(scenario)  # the scenario as run (its e and t_end applied)


@pytest.fixture
def fake_engine(monkeypatch):
    from treeimpact.compare.runs import backends

    monkeypatch.setitem(backends.BACKENDS, "fake", backends.Backend(
        "fake", f"{__name__}:_explode_or_diverge", None, "test engine",
        options_ref=f"{__name__}:FAKE_OPTIONS"))
    return "fake"


def test_failing_point_is_recorded_and_the_sweep_goes_on(tmp_path, fake_engine):
    # central-leader: l = 1 m; a clamp height of 0.8 m is invalid on the 0.5 m trunk only
    grid = ["restitution=0.2,0.5,0.9", "trunk.clamp_height=0.315,0.8", "trunk.length=0.5,1"]
    res = run_sweep("central-leader", grid, tmp_path, backends=["analytic", fake_engine],
                    workers=0, identify=False)
    df = res.table
    assert len(df) == 3 * 2 * 2 * 2  # every (point, target) has a row, none is lost
    combo = (df["trunk.clamp_height"] == 0.8) & (df["trunk.length"] == 0.5)
    assert set(df[combo]["status"]) == {INVALID} and combo.sum() == 3 * 2
    assert df[combo]["error"].str.contains("trunk.clamp_height").all()
    valid = df[~combo]
    fake = valid[valid["target"] == "fake"]
    assert set(fake[fake["restitution"] == 0.2]["status"]) == {"ok"}
    div = fake[fake["restitution"] == 0.5]
    assert set(div["status"]) == {"diverged"} and div["error"].str.contains("energy grew").all()
    assert div[["x_max", "T0"]].isna().all().all()  # a diverged row carries no numbers
    bad = fake[fake["restitution"] == 0.9]
    assert set(bad["status"]) == {"failed"} and bad["error"].str.contains("RuntimeError").all()
    assert set(valid[valid["target"] == "analytic"]["status"]) == {"ok"}


def test_value_invalid_at_every_point_is_refused_before_anything_runs(tmp_path):
    with pytest.raises(ParameterError) as exc:
        run_sweep("central-leader", ["restitution=0.2,2", "crown_ratio=0,1"], tmp_path / "s",
                  workers=0, identify=False)
    msg = str(exc.value)
    assert "\n" not in msg and msg.startswith("--grid 'restitution=0.2,2.0': restitution = 2.0")
    assert "allowed [0, 1]" in msg  # analytic.Contact's range of the restitution
    assert not (tmp_path / "s").exists()
    with pytest.raises(ParameterError, match=r"^--grid 'option.foo=1.0': no backend .*"
                                             r"analytic.* allowed: "):
        run_sweep("central-leader", ["option.foo=1"], tmp_path / "s", workers=0)


def _infinite_x_max(scenario):
    """A stand-in engine that returns (does not raise) a run whose x_max blew up."""
    result = simulate(scenario)  # the scenario as run (its e and t_end applied)
    result.metrics["x_max"] = math.inf
    return result


def test_run_returning_infinite_metrics_is_recorded_as_diverged(tmp_path, monkeypatch):
    from treeimpact.compare.runs import backends

    monkeypatch.setitem(backends.BACKENDS, "inf", backends.Backend(
        "inf", f"{__name__}:_infinite_x_max", None, "test engine",
        options_ref=f"{__name__}:T_END_OPTIONS"))
    res = run_sweep("central-leader", ["restitution=0.3"], tmp_path, backends=["analytic", "inf"],
                    workers=0, identify=False)
    row = res.table.set_index("target").loc["inf"]
    assert row["status"] == "diverged" and "x_max" in row["error"]
    assert math.isnan(row["x_max"]) and math.isnan(row["T0"])


def _dies_at_half(scenario):
    """A stand-in engine whose worker process dies (as in a crash) at e = 0.5."""
    import multiprocessing
    import os

    if scenario.contact.restitution == 0.5 and multiprocessing.parent_process() is not None:
        os._exit(1)
    return simulate(scenario)  # the scenario as run (its e and t_end applied)


def test_worker_process_dying_costs_only_its_point(tmp_path, monkeypatch):
    from treeimpact.compare.runs import backends

    monkeypatch.setitem(backends.BACKENDS, "crash", backends.Backend(
        "crash", f"{__name__}:_dies_at_half", None, "test engine",
        options_ref=f"{__name__}:T_END_OPTIONS"))
    res = run_sweep("central-leader", ["restitution=0.1,0.3,0.5,0.7,0.9"], tmp_path,
                    backends=["analytic", "crash"], workers=2, identify=False, progress=False)
    df = res.table.set_index(["target", "restitution"])
    assert len(df) == 10
    assert df.loc[("crash", 0.5), "status"] == "failed"
    assert "worker process died" in df.loc[("crash", 0.5), "error"]
    others = df.drop(index=("crash", 0.5))
    assert set(others["status"]) == {"ok"}
    # the rows of the surviving points are the in-process runs' numbers
    ref = simulate(apply_point(load_scenario("central-leader"), {"restitution": 0.7})[0])
    assert df.loc[("crash", 0.7), "x_max"] == ref.metrics["x_max"]


def test_segments_one_is_the_sdof_trunk_and_shares_its_run(monkeypatch):
    from treeimpact.compare.runs import backends
    from treeimpact.compare.studies.sweep.plan import make_targets, plan

    monkeypatch.setitem(backends.BACKENDS, "eng", backends.Backend(
        "eng", f"{__name__}:_engine_with_trunk", None, "test engine",
        options_ref=f"{__name__}:TRUNK_OPTIONS"))
    targets = make_targets(["analytic", "eng"], ladder=True)
    tasks, immediate = plan(load_scenario("central-leader"), parse_grid(["segments=1,4"]),
                            targets, identify=False)
    assert not immediate
    opts = {(pk, t.id): dict(task.options) for task in tasks for _, pk, t, _ in task.rows}
    one, four = '[["segments",1]]', '[["segments",4]]'
    assert opts[(one, "eng-chain")] == {"trunk": "sdof", "pendulum": "linear"}
    assert opts[(one, "eng-chain-full")] == {"trunk": "sdof", "pendulum": "full"}
    assert opts[(four, "eng-chain")] == {"trunk": "chain", "pendulum": "linear", "segments": 4}
    assert opts[(four, "eng-sdof")] == {"trunk": "sdof", "pendulum": "linear"}
    # one run for the SDOF rung at both points and the chain rung at segments = 1
    shared = [t for t in tasks if dict(t.options) == {"trunk": "sdof", "pendulum": "linear"}]
    assert len(shared) == 1 and len(shared[0].rows) == 3


def _engine_with_trunk(scenario, *, trunk="chain", segments=None,
                       pendulum="linear"):  # pragma: no cover - planned, never run
    raise AssertionError("not run")


def _takes_segments(scenario, *, segments=None):
    """A stand-in engine that takes ``segments`` (and ignores it)."""
    return simulate(scenario)  # the scenario as run (its e and t_end applied)


def test_unavailable_option_is_a_skipped_row_not_a_crash(tmp_path, fake_engine, monkeypatch):
    from treeimpact.compare.runs import backends

    monkeypatch.setitem(backends.BACKENDS, "seg", backends.Backend(
        "seg", f"{__name__}:_takes_segments", None, "test engine",
        options_ref=f"{__name__}:SEGMENTS_OPTIONS"))
    res = run_sweep("central-leader", ["restitution=0.2", "segments=4"], tmp_path,
                    backends=["analytic", fake_engine, "seg"], workers=0, identify=False)
    row = res.table.set_index("target")
    assert row.loc["analytic", "status"] == "ok"  # segments does not apply to the reference
    assert row.loc["seg", "status"] == "ok"
    assert row.loc["fake", "status"] == "skipped"
    assert "--segments" in row.loc["fake", "error"]
    with pytest.raises(ParameterError, match=r"^--grid 'segments=4': no backend .* takes"):
        run_sweep("central-leader", ["segments=4"], tmp_path / "b",
                  backends=["analytic", fake_engine], workers=0)


def _metric_frame(df):
    cols = ["point", "target", "status", *METRIC_KEYS, "id.M_T"]
    return df[cols].sort_values(["point", "target"]).reset_index(drop=True)


def test_resume_after_interruption_loses_nothing(tmp_path):
    grid = ["restitution=0.1:0.9:5", "mass_ratio=0.5,1,2"]
    seen = []

    def interrupt(rows):
        seen.extend(rows)
        if len(seen) >= 4:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_sweep("open-center", grid, tmp_path / "a", workers=2, on_rows=interrupt,
                  progress=False)
    journal = tmp_path / "a" / JOURNAL
    first = read_table(tmp_path / "a")
    assert 4 <= len(first) < 15
    with open(journal, "a") as fh:  # a sweep killed while writing a row
        fh.write('open-center,"[[""restitution"",0.9],[""mass_')
    res = run_sweep("open-center", grid, tmp_path / "a", workers=2, progress=False)
    assert res.rows_done_before == len(first)
    assert res.rows_written == 15 - len(first)
    raw = read_table(tmp_path / "a", dedupe=False)
    assert len(raw) == 15 and not raw.duplicated(["point", "target"]).any()
    fresh = run_sweep("open-center", grid, tmp_path / "b", workers=0, progress=False)
    pd.testing.assert_frame_equal(_metric_frame(res.table), _metric_frame(fresh.table))
    parquet = pd.read_parquet(tmp_path / "a" / TABLE)
    assert len(parquet) == 15


def test_progress_bar_counts_every_row(tmp_path, capsys):
    run_sweep("central-leader", ["restitution=0.1,0.2,0.3"], tmp_path, workers=0, identify=False,
              progress=True)
    err = capsys.readouterr().err
    assert "sweep: 100%" in err and "3/3" in err  # tqdm's bar on stderr


def test_resume_refuses_another_scenario_in_the_same_directory(tmp_path):
    run_sweep("open-center", ["restitution=0.1"], tmp_path, workers=0, identify=False)
    with pytest.raises(ParameterError, match="--out"):
        run_sweep("central-leader", ["restitution=0.1"], tmp_path, workers=0, identify=False)


def test_dask_local_cluster_gives_the_process_pool_results(tmp_path):
    distributed = pytest.importorskip("distributed")
    grid = ["restitution=0.1,0.4,0.7", "crown_ratio=0,1.5"]
    local = run_sweep("central-leader", grid, tmp_path / "pool", workers=2, progress=False)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as cluster:
        dask = run_sweep("central-leader", grid, tmp_path / "dask",
                         scheduler=cluster.scheduler_address, progress=False)
    assert len(dask.table) == len(local.table) == 6
    # same inputs, same deterministic solver: identical to the last bit
    pd.testing.assert_frame_equal(_metric_frame(dask.table), _metric_frame(local.table))


def test_bad_scheduler_address_is_one_line(tmp_path):
    with pytest.raises(ParameterError, match="--scheduler"):
        run_sweep("central-leader", ["restitution=0.1"], tmp_path, scheduler="not-a-scheme://x:1")


# --------------------------------------------------------------------------- maps


def _synthetic_ladder():
    """Two points; a ladder analytic -> soft -> e-sdof -> e-chain with known steps."""
    rows = []
    values = {"p1": {"analytic": 1.0, "soft": 1.01, "e-sdof": 1.011, "e-chain": 1.2},
              "p2": {"analytic": 1.0, "soft": 1.3, "e-sdof": 1.3, "e-chain": 1.31}}
    meta = {"analytic": ("analytic", "newton", None), "soft": ("soft", "contact", "analytic"),
            "e-sdof": ("e", "engine", "soft"), "e-chain": ("e", "trunk", "e-sdof")}
    for i, (p, vals) in enumerate(values.items()):
        for t, v in vals.items():
            b, k, prev = meta[t]
            rows.append({"scenario": "s", "point": p, "target": t, "backend": b, "kind": k,
                         "previous": prev, "status": "ok", "error": None, "wall_s": 0.1,
                         "t_end": 0.1, "task": f"{p}{t}", "worker": "w", "finished": 0.0,
                         "restitution": 0.1 * (i + 1), "x_max": v})
    return pd.DataFrame(rows)


def test_discrepancy_is_relative_to_analytic_and_dominant_rung_is_the_largest_step():
    d = discrepancies(_synthetic_ladder(), metrics=("x_max",)).set_index(["point", "target"])
    assert d.loc[("p1", "e-chain"), "rel"] == pytest.approx(0.2, rel=1e-12)
    assert d.loc[("p1", "e-chain"), "step"] == pytest.approx(1.2 / 1.011 - 1, rel=1e-12)
    assert d.loc[("p1", "e-chain"), "dominant"] == "trunk"  # 18.7 % step vs 1 % contact
    assert d.loc[("p2", "e-chain"), "dominant"] == "contact"  # 30 % contact vs 0.8 % trunk
    assert d.loc[("p2", "e-sdof"), "dominant"] == "contact"


def test_validity_map_of_soft_against_analytic(tmp_path):
    res = run_sweep("central-leader", ["restitution=0.3,0.6", "crown_ratio=0,1"], tmp_path / "s",
                    backends=["analytic", "soft"], workers=2, progress=False)
    d = discrepancies(res.table, metrics=("x_max",))
    assert set(d["target"]) == {"soft"} and set(d["dominant"]) == {"contact"}
    # independently: the soft and exact runs at one point, straight from the backends
    scen, _ = apply_point(load_scenario("central-leader"), {"restitution": 0.6, "crown_ratio": 1.0})
    from treeimpact.analytic.contact.soft import simulate_soft

    want = simulate_soft(scen).metrics["x_max"] / simulate(scen).metrics["x_max"] - 1
    got = d[(d["restitution"] == 0.6) & (d["crown_ratio"] == 1.0)]["rel"].item()
    assert got == pytest.approx(want, rel=1e-12)
    figs = validity_maps(res.table, tmp_path / "fig")
    assert [f["target"] for f in figs] == ["soft"]
    assert figs[0]["path"].stat().st_size > 10_000
    assert figs[0]["axes"] == ["restitution", "crown_ratio"]
    xmax = next(s for s in figs[0]["summary"] if s["metric"] == "x_max")
    # x_max: the contact model moves it by at most b t_c <= 1.5 % (tolerances.toml)
    assert xmax["within"] == 1.0 and abs(xmax["worst_rel"]) <= 0.015


def test_study_stands_alone_and_is_a_report_section_with_its_figures_in_place(tmp_path):
    from treeimpact.compare.report.studies import StudySection
    from treeimpact.compare.report.validity.study import write_study

    res = run_sweep("central-leader", ["restitution=0.3,0.6", "crown_ratio=0,1"], tmp_path / "s",
                    backends=["analytic", "soft"], workers=0, progress=False)
    paths = write_study(tmp_path / "study", {"validity": res.out})
    names = sorted(p.name for p in paths["figures"])
    # soft's validity map and one identification map per target (analytic, soft)
    assert names == ["identification-analytic.png", "identification-soft.png",
                     "validity-soft-restitution-crown_ratio.png"]
    md = paths["md"].read_text()
    assert all(f"]({n})" in md for n in names)  # study.md shows every figure
    table = pd.read_parquet(paths["table"])
    assert len(table) == 8 and set(table["sweep"]) == {"validity"}
    page = paths["html"].read_text()
    assert page.count("<img ") == 3 and "<table>" in page
    sec = StudySection(tmp_path / "study", page_dir=tmp_path)
    html = sec.render("html")
    # each figure in place (linked relative to the page), none repeated after the text
    assert html.count('src="study/') == 3 and sec.images == []
    assert html.index("Validity maps") < html.index('src="study/') \
        < html.index("Identification maps")
    # headings nest under the section's own heading (the report's <summary>, an h2)
    assert "<h2" not in html and "<h1" not in html and "<h3>Sweep" not in html
    assert "<h4>Validity maps</h4>" in html
    text = sec.render("md")
    assert "\n#### Validity maps" in text and "\n# " not in text and "\n## Validity" not in text
    assert "](study/validity-soft-restitution-crown_ratio.png)" in text  # report.md shows it too


def test_a_study_without_speed_curves_says_where_its_engine_runs_are(tmp_path, fake_engine):
    """A study whose engine runs are on its validity maps and which draws no speed-accuracy
    curves says so (not 'No engine in this study' above its engine runs)."""
    from treeimpact.compare.report.validity.study import write_study

    res = run_sweep("central-leader", ["restitution=0.2,0.3"], tmp_path / "s",
                    backends=["analytic", fake_engine], workers=0, progress=False)
    paths = write_study(tmp_path / "study", {"validity": res.out})
    for page in (paths["html"].read_text(), paths["md"].read_text()):
        assert "No engine" not in page
        assert "draws no speed-accuracy curves; its 2 fake runs are on the validity maps" \
            in page


def test_long_runs_are_their_own_worker_calls_and_short_ones_are_batched(fake_engine):
    from treeimpact.compare.studies.sweep.cost import chunks as _chunks
    from treeimpact.compare.studies.sweep.plan import make_targets, plan

    tasks, _ = plan(load_scenario("central-leader"), parse_grid(["restitution=0:0.9:40"]),
                    make_targets(["analytic", fake_engine]), identify=False)
    chunks = _chunks(tasks, 2)
    assert sorted(t.key for c in chunks for t in c) == sorted(t.key for t in tasks)
    # an engine of unknown cost (1 s a run): one run a call, so Ctrl-C loses little
    assert all(len(c) == 1 for c in chunks if c[0].backend.name == "fake")
    analytic = [c for c in chunks if c[0].backend.name == "analytic"]
    assert all({t.backend.name for t in c} == {"analytic"} for c in analytic)
    assert len(analytic) == 20  # 40 runs // (8 calls x 2 workers) = 2 a call

    many, _ = plan(load_scenario("central-leader"), parse_grid(["restitution=0:0.9:400"]),
                   make_targets(["analytic"]), identify=False)
    assert max(len(c) for c in _chunks(many, 2)) == 25  # 400 // (8 calls x 2 workers)
    # the call budget bounds a call: 1 s / 5 ms (the registry's analytic run) = 200 runs
    assert max(len(c) for c in _chunks(many * 5, 1)) == 200


def test_a_cheap_run_is_repeated_per_record_so_its_fits_spread_over_the_workers(fake_engine):
    """Records of one run (record.* axes) share the run when it costs more than their
    analysis (an engine, 1 s); a run cheaper than a fit (analytic, 5 ms) is made once per
    record, so 18 fits of one record grid do not queue on one worker (the default study's
    sampling grid did: 10 s on one core)."""
    from treeimpact.compare.runs.backends import get_backend
    from treeimpact.compare.studies.ident_records import ANALYSIS
    from treeimpact.compare.studies.sweep.cost import ANALYSIS_COST
    from treeimpact.compare.studies.sweep.plan import make_targets, plan

    grid = parse_grid(["restitution=0.1", "record.rate=1e3,5e3,2e4", "record.seed=1,2"])
    tasks, _ = plan(load_scenario("central-leader"), grid,
                    make_targets(["analytic", fake_engine]), identify=False,
                    analysis=ANALYSIS)
    by = {b: [t for t in tasks if t.backend.name == b] for b in ("analytic", "fake")}
    assert get_backend("analytic").cost({}) < ANALYSIS_COST <= get_backend("fake").cost({})
    assert len(by["analytic"]) == 6 and all(len(t.rows) == 1 for t in by["analytic"])
    assert len(by["fake"]) == 1 and len(by["fake"][0].rows) == 6


def test_a_worker_makes_a_run_repeated_per_record_once_for_its_consecutive_tasks(monkeypatch):
    """The tasks that repeat one run per record (above) share Task.run; a worker making them
    one after the other makes the run once (compare.studies.sweep.execute._LAST_RUN) and gives
    every row the outcome the repeated runs gave; a task of another run makes its own."""
    from treeimpact.compare.studies.ident_records import ANALYSIS
    from treeimpact.compare.studies.sweep import execute
    from treeimpact.compare.studies.sweep.plan import make_targets, plan

    grid = parse_grid(["restitution=0.1,0.5", "record.rate=1e3,5e3,2e4"])
    tasks, _ = plan(load_scenario("central-leader"), grid, make_targets(["analytic"]),
                    identify=False, analysis=ANALYSIS)
    assert len(tasks) == 6 and len({t.run for t in tasks}) == 2  # 2 runs x 3 records
    made = []
    real = execute.attempt
    monkeypatch.setattr(execute, "attempt", lambda *a: made.append(a) or real(*a))
    monkeypatch.setattr(execute, "_LAST_RUN", [None, None])
    shared = execute.run_chunk(tasks)
    assert len(made) == 2
    monkeypatch.setattr(execute, "_run", lambda t: real(t.backend, t.scenario, t.options))
    alone = execute.run_chunk(tasks)
    drop = ("wall_s", "worker")
    assert [[{k: v for k, v in r.items() if k not in drop} for r in rows] for rows in shared] \
        == [[{k: v for k, v in r.items() if k not in drop} for r in rows] for rows in alone]


def test_identification_map_matches_the_documented_floor_and_finding(tmp_path):
    res = run_sweep("central-leader", ["restitution=0,0.1", "impactor.mass=132.4,140"], tmp_path,
                    workers=0, progress=False)
    df = res.table.set_index(["restitution", "impactor.mass"])
    rel = (df["id.M_T"] - df["truth.M_T"]) / df["truth.M_T"]
    # tolerances.toml [identification]: floor of the procedure at e = 0 is 3 % on M_T;
    # [[finding]] central-leader at e = 0.1: M_T low by 10-22 %
    assert abs(rel[(0.0, 132.4)]) <= 0.03
    assert -0.22 <= rel[(0.1, 132.4)] <= -0.10
    figs = identification_maps(res.table, tmp_path / "fig")
    assert len(figs) == 1 and figs[0]["axes"] == ["restitution", "impactor.mass"]
    assert figs[0]["path"].exists()


def test_speed_point_is_max_relative_error_and_wall_time_per_simulated_second():
    base = {"scenario": "s", "status": "ok", "error": None, "t_end": 0.1, "dt": 1e-5,
            "contact_stiffness": 1e9, "point": "p"}
    metrics = {"x_max": 1.0, "t_xmax": 2.0, "t_sep": 3.0, "impact_loss": 4.0,
               "energy_transferred": 5.0, "theta_b": 6.0}
    eng = {k: v * (1.01 if k == "t_sep" else 1.0) for k, v in metrics.items()}
    eng["theta_b"] = 6.0 * 0.97  # the largest error: 3 %
    df = pd.DataFrame([base | {"target": "soft", "wall_s": 9.0} | metrics,
                       base | {"target": "analytic", "wall_s": 0.1} | metrics,
                       base | {"target": "mujoco", "wall_s": 0.25} | eng])
    p = speed_points(df, "mujoco").iloc[0]
    assert p["cost"] == pytest.approx(2.5) and p["err_soft"] == pytest.approx(0.03)


# --------------------------------------------------------------------------- command line


def test_treeimpact_sweep_writes_table_maps_and_study(tmp_path, capsys):
    from treeimpact.compare.interface.cli import main

    out = tmp_path / "sw"
    rc = main(["sweep", "--grid", "restitution=0.2:0.6:3", "--grid", "mass_ratio=0.5,1",
               "--backend", "analytic", "--workers", "0", "--out", str(out)])
    assert rc == 0
    for name in ("results.csv", "results.parquet", "study.md", "study.html", "study.json"):
        assert (out / name).exists(), name
    assert len(read_table(out)) == 6
    rc = main(["sweep", "--grid", "restitution=0:0.9", "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "\n" not in err and "--grid 'restitution=0:0.9'" in err
    assert "START:STOP:COUNT" in err


@pytest.mark.parametrize("argv, words", [
    (["--grid", "restitution=abc"], ["--grid 'restitution=abc'", "not a number",
                                     "START:STOP:COUNT"]),
    (["--grid", "nosuch=1"], ["--grid 'nosuch=1'", "unknown name", "allowed"]),
    (["--grid", "restitution=2"], ["--grid 'restitution=2.0'", "contact.restitution",
                                          "allowed [0, 1]"]),
    (["--grid", "segments=0,4"], ["--grid 'segments=0,4'", "allowed [1, 1000]"]),
    (["--grid", "dt=-1e-5"], ["--grid 'dt=-1e-5'", "allowed (0, 0.001] s"]),
    (["--grid", "restitution=0.1", "--workers", "-1"], ["--workers", "integer >= 0"]),
    (["--grid", "restitution=0.1", "--backend", "nosuch"], ["--backend 'nosuch'", "allowed"]),
    (["--grid", "restitution=0.1", "--scheduler", "nohost"], ["--scheduler 'nohost'", "tcp://HOST:PORT"]),
    # a fixed option is checked against the backend's OPTIONS before anything runs
    (["--grid", "restitution=0.1", "--backend", "analytic,mujoco", "--option", "foo=bar"],
     ["--option 'foo=bar'", "has no option 'foo'", "allowed"]),
    (["--grid", "restitution=0.1", "--backend", "analytic,mujoco", "--option", "dt=-1"],
     ["--option 'dt=-1'", "allowed (0, 0.001] s"]),
    (["--grid", "restitution=0.1", "--sensitivity-scenario", "open-center"],
     ["--sensitivity-scenario", "used with --preset"]),
])
def test_bad_sweep_input_is_one_line_and_exit_2(tmp_path, capsys, argv, words):
    from treeimpact.compare.interface.cli import main

    rc = main(["sweep", *argv, "--backend", "analytic", "--out", str(tmp_path / "o")]
              if "--backend" not in argv else ["sweep", *argv, "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err.strip()
    assert rc == 2 and "\n" not in err and "Traceback" not in err
    for w in words:
        assert w in err, (w, err)
    assert not (tmp_path / "o" / "results.csv").exists()  # nothing ran


def test_interrupted_sweep_command_says_how_to_resume_and_exits_130(tmp_path, capsys,
                                                                     monkeypatch):
    from treeimpact.compare.interface import api_studies
    from treeimpact.compare.interface.cli import main

    def interrupted(*args, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(api_studies, "sweep", interrupted)  # the API function the command calls
    rc = main(["sweep", "--grid", "restitution=0.1", "--backend", "analytic", "--out",
               str(tmp_path)])
    err = capsys.readouterr().err.strip()
    assert rc == 130 and "\n" not in err and "rerun the same command to resume" in err



def test_map_cells_print_their_values_outline_the_tolerance_and_say_why_na():
    """A colour that saturates never hides a value: +300 % prints as such, the colour bar
    gets an arrow; a cell within 5 % is outlined; a cell without a value says why."""
    import matplotlib
    import pandas as pd
    from matplotlib.figure import Figure
    from matplotlib.patches import Rectangle

    from treeimpact.compare.studies.sweep.map_cells import _extend, _heat
    from treeimpact.compare.studies.sweep.validity_maps import _validity_caption

    matplotlib.use("Agg")
    cell = pd.DataFrame({"restitution": [0.1, 0.5, 0.9], "crown_ratio": [0.0, 0.0, 0.0],
                         "rel": [0.01, 3.0, math.nan], "value": [1.0, 4.0, 1.0],
                         "analytic": [0.99, 1.0, math.nan]})
    ax = Figure().add_subplot()
    _heat(ax, cell, "restitution", "crown_ratio", "rel", 0.05, "x_max", vmax=1.0)
    texts = [t.get_text() for t in ax.texts]
    # why, in a word the cell holds; the caption spells the words out
    assert texts == ["+1%", "+300%", "no ref"]
    assert "no ref: the paper's model has none" in _validity_caption("x", "restitution",
                                                                       "crown_ratio", 0.05)
    outlined = [p.get_xy() for p in ax.patches if isinstance(p, Rectangle)]
    assert outlined == [(-0.5, -0.5)]  # only the 1 % cell, on the grid's own cell
    assert _extend(cell["rel"], 1.0) == "max" and _extend(cell["rel"], 5.0) == "neither"
    assert all(t.get_fontsize() >= 7 for t in ax.texts)
    assert all(lbl.get_fontsize() >= 9 for lbl in ax.get_xticklabels())


def test_map_labels_fit_their_cells_and_ticks_read_in_the_texts_units():
    """An 8 x 6 map of the default study: every printed value and every 'why no value'
    word lies inside its cell; a contact duration reads in ms, as the text gives it; the
    colour bar reads in %, as the cells."""
    import itertools

    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from treeimpact.compare.studies.sweep.map_cells import (
        _grid_figure,
        _heat,
        _percent_colorbar,
        colour_scale,
    )

    durations = np.geomspace(2e-4, 2e-2, 8)
    crowns = np.linspace(0, 4, 6)
    rows = []
    for n, (d, c) in enumerate(itertools.product(durations, crowns)):
        failed = n % 5 == 0
        rows.append({"contact_duration": d, "crown_ratio": c,
                     "rel": math.nan if failed else (-1) ** n * 2.345,
                     "id_error": "not identifiable: xi = -0.8: no decay" if failed else None})
    cell = pd.DataFrame(rows)
    scale = colour_scale(0.05)
    fig, axes = _grid_figure(3, 8, 6)
    FigureCanvasAgg(fig)
    for ax in axes:
        im = _heat(ax, cell, "contact_duration", "crown_ratio", "rel", 0.05, "M_T",
                   scale=scale)
    cb = fig.colorbar(im, ax=axes)
    _percent_colorbar(cb, scale, "(identified - true) / true (%)")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in axes:
        (x0, y0), (x1, y1) = ax.transData.transform([(0, 0), (1, 1)])
        width, height = abs(x1 - x0), abs(y1 - y0)
        for t in ax.texts:
            box = t.get_window_extent(renderer)
            assert box.width < width and box.height < height, (t.get_text(), box, width)
        assert [lbl.get_text() for lbl in ax.get_xticklabels()][:2] == ["0.2", "0.386"]
        assert ax.get_xlabel() == "contact duration (ms)"
        assert ax.get_ylabel() == "m_f / m_trunk (1)"  # a dimensionless axis states "(1)"
    assert {lbl.get_text() for lbl in cb.ax.get_yticklabels()} >= {"+100 %", "0", "-10 %"}


def test_every_map_axis_of_a_registry_input_states_its_display_unit():
    """A study map's axis reads as the report's figures do (compare/tests/test_report.py
    test_every_axis_has_a_unit): the registry's words and display unit, "(1)" for a
    dimensionless number; a caption's prose leaves "(1)" out."""
    from treeimpact.analytic.model.registry import PARAMETERS
    from treeimpact.compare.studies.sweep.map_cells import _label, axis_label

    swept = [p for p in PARAMETERS if p.sweep is not None]
    assert {"restitution", "crown_ratio", "contact_duration"} <= {p.sweep for p in swept}
    for p in swept:
        assert axis_label(p.sweep) == f"{p.axis} ({p.shown_unit})", p.name
        assert _label(p.sweep).endswith(")") == (p.shown_unit != "1"), p.name
    assert axis_label("restitution") == "e (1)" and _label("restitution") == "e"


def test_every_map_of_a_study_shares_one_colour_scale_and_letters_only_where_shown(tmp_path):
    """Validity and identification maps of one study on one colour scale; the study's text
    lists the rung letters a map prints, none when the maps show steps (no letters)."""
    from treeimpact.compare.report.validity.study import write_study
    from treeimpact.compare.studies.sweep.maps import DEFAULT_TOLERANCE, colour_scale

    res = run_sweep("central-leader", ["restitution=0.3,0.6", "crown_ratio=0,1"],
                    tmp_path / "s", backends=["analytic", "soft"], workers=0, progress=False)
    scales = [m["scale"] for m in validity_maps(res.table, tmp_path / "v", value="step")
              + validity_maps(res.table, tmp_path / "r")
              + identification_maps(res.table, tmp_path / "i")]
    assert len(scales) >= 3 and all(s == colour_scale(DEFAULT_TOLERANCE) for s in scales)
    step = write_study(tmp_path / "step", {"validity": res.out}, value="step")
    assert json.loads(step["json"].read_text())["rung_letters"] == []
    assert "Letters on the maps" not in step["html"].read_text()
    rel = write_study(tmp_path / "rel", {"validity": res.out}, value="rel")
    letters = json.loads(rel["json"].read_text())["rung_letters"]
    assert [x["letter"] for x in letters] == ["C"]  # soft vs analytic: the contact model


def test_the_identification_caption_counts_reasons_whatever_the_rows_order():
    """Cells whose procedure stopped for one reason count as one reason, whatever numbers
    its message carries, and the caption does not follow the order the sweep's workers
    finished in (it did: two runs of one study wrote two captions)."""
    from treeimpact.compare.studies.sweep.identification_maps import _why_not_identified

    stop = ("identification: the bodies do not move together before x_max (the pendulum "
            "is {} mm off the trunk on the way to the peak, above 0.113 mm)")
    rows = [{"rel": math.nan, "id_error": stop.format(d)} for d in (0.117, 4.91, 2.14)]
    rows += [{"rel": math.nan, "id_error": "identification: eqs 42-43's x0 does not hold"}] * 3
    rows += [{"rel": 0.01, "id_error": None}]
    forward = _why_not_identified(pd.DataFrame(rows))
    assert forward == _why_not_identified(pd.DataFrame(rows[::-1]))
    assert forward == ("eqs 42-43's x0 does not hold (3); "
                       "the bodies do not move together before x_max (3)")
