"""A study run beside the report (compare/report/validity/study_job.py, ``report
--with-study``): its section in the page, its failure as the report's, its end when the
report stops."""

from __future__ import annotations

import json
import sys
import time

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.interface.cli import main
from treeimpact.compare.interface.api_studies import PROGRAM
from treeimpact.compare.report import write_report
from treeimpact.compare.report.validity.study_job import StudyJob
from treeimpact.compare.runs.cache import RunCache


def _quick(job: StudyJob, *grid: str) -> StudyJob:
    """The job running a two-point analytic sweep instead of its preset (seconds, not 30)."""
    job.argv = [*PROGRAM, "sweep", "--scenario",
                "open-center", "--backend", "analytic", "--workers", "0", "--out",
                str(job.out), *(a for g in grid for a in ("--grid", g))]
    return job


def test_a_study_run_beside_the_report_becomes_its_section(tmp_path):
    job = _quick(StudyJob("default", tmp_path / "out" / "study", PROGRAM),
                 "restitution=0.1,0.2")
    paths = write_report(tmp_path / "out", scenarios=["open-center"], runs=RunCache(),
                         engines=(), study_jobs=(job.start(),))
    assert (tmp_path / "out" / "study" / "study.json").exists()
    data = json.loads(paths["json"].read_text())
    assert len(data["studies"]) == 1
    wall = data["runs"]["wall_s"]
    assert wall["study default (a child process beside all of the above, from its start "
                "to its end)"] == job.wall_s > 0
    assert "waiting for the studies" in wall


def test_a_failed_study_fails_with_its_exit_code_and_last_line(tmp_path):
    job = _quick(StudyJob("default", tmp_path / "study", PROGRAM), "restitution=2").start()
    with pytest.raises(ParameterError, match=r"--with-study default: .*exit code 2: .*restitution"):
        job.result()


def test_a_study_that_failed_stops_the_report_before_its_fits(tmp_path, monkeypatch):
    """The report looks at its studies after its runs: one that already failed ends it
    there, not after the record fits and figures."""
    import treeimpact.compare.report as report

    job = _quick(StudyJob("default", tmp_path / "out" / "study", PROGRAM),
                 "restitution=2").start()
    while job._proc.poll() is None:
        time.sleep(0.1)

    def no_fit(task):
        pytest.fail("fitted records for a report whose study had failed")

    monkeypatch.setattr(report, "fit_one", no_fit)  # the name the report pools
    with pytest.raises(ParameterError, match="exit code 2"):
        write_report(tmp_path / "out", scenarios=["open-center"], runs=RunCache(),
                     engines=(), study_jobs=(job,))


def test_an_unknown_preset_is_refused_before_anything_runs(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--with-study", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["treeimpact: error: --with-study 'nope': allowed default, full, design"]
    assert not (tmp_path / "study").exists()


def test_stopping_the_report_ends_the_study(tmp_path):
    """stop() ends the study by its SIGTERM (returncode -15), not by waiting out its 60 s
    (returncode 0); no wall clock read (a stop that waited would take the 60 s: the hang
    guard)."""
    import signal

    job = StudyJob("default", tmp_path / "study", PROGRAM)
    job.argv = [sys.executable, "-c", "import time; time.sleep(60)"]
    job.start()
    job.stop()
    assert job._proc.poll() == -signal.SIGTERM


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_command_and_its_group_signalled_as_timeout_does_end_with_the_study(tmp_path):
    """GNU timeout sends SIGTERM to the command and then to its process group: the report
    gets two, its study and workers one each. All end, the report with 130."""
    import os
    import signal
    import subprocess

    proc = subprocess.Popen([sys.executable, "-m", "treeimpact.compare.interface.cli", "report",
                             "--out", str(tmp_path), "--with-study", "default"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    deadline = time.monotonic() + 60  # a hang guard, not a speed check
    while not (tmp_path / "study" / "sweep.json").exists() and \
            not list((tmp_path / "study").glob("*/sweep.json")):
        assert time.monotonic() < deadline and proc.poll() is None, "the study never started"
        time.sleep(0.2)
    time.sleep(1.0)  # runs under way in both processes
    os.kill(proc.pid, signal.SIGTERM)
    os.killpg(proc.pid, signal.SIGTERM)
    try:
        code = proc.wait(30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert code == 130, proc.stderr.read()
    deadline = time.monotonic() + 60  # a hang guard, not a speed check: one left fails
    while _alive_in_group(proc.pid):  # the study and every worker end too
        assert time.monotonic() < deadline, _alive_in_group(proc.pid)
        time.sleep(0.2)


def _alive_in_group(pgid: int) -> list[str]:
    """The processes of group ``pgid`` that still run (not the zombies init has yet to
    reap), from /proc: [(pid, command)]."""
    from pathlib import Path

    alive = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            text = stat.read_text()
        except OSError:  # ended meanwhile
            continue
        fields = text.rsplit(")", 1)[1].split()
        if int(fields[2]) == pgid and fields[0] != "Z":
            alive.append(f"{stat.parent.name} {text.split(' ', 2)[1]}")
    return alive


def test_the_reports_trees_are_its_studys_sensitivity_trees(tmp_path):
    """report --scenario ... --with-study: the study's sensitivity part runs on the report's
    trees and its maps on the first of them (issue 41: they were central-leader's on a
    user's tree): a shipped name as it is, a file by its absolute path, a Scenario object written
    into the study's own folder (it loads back equal)."""
    from dataclasses import replace

    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.analytic.model.scenario_toml import scenario_toml

    tree = replace(load_scenario("open-center"), name="my-tree")
    path = tmp_path / "my-tree.toml"
    path.write_text(scenario_toml(tree))
    other = replace(tree, name="other-tree")
    job = StudyJob("default", tmp_path / "study", PROGRAM,
                   scenarios=["central-leader", str(path), other])
    flags = [job.argv[i + 1] for i, a in enumerate(job.argv) if a == "--sensitivity-scenario"]
    written = tmp_path / "study" / "scenarios" / "other-tree.toml"
    assert flags == ["central-leader", str(path.resolve()), str(written.resolve())]
    assert load_scenario(written) == other
    assert job.argv[job.argv.index("--scenario") + 1] == "central-leader"  # its maps' tree
    assert "--sensitivity-scenario" not in StudyJob("default", tmp_path / "s2", PROGRAM).argv
    assert "--scenario" not in StudyJob("default", tmp_path / "s3", PROGRAM).argv  # preset's
    mine = StudyJob("default", tmp_path / "s4", PROGRAM, scenarios=[str(path)])
    assert mine.argv[mine.argv.index("--scenario") + 1] == str(path.resolve())
    design = StudyJob("design", tmp_path / "d", PROGRAM, scenarios=[str(path), "open-center"])
    assert design.argv[design.argv.index("--scenario") + 1] == str(path.resolve())
    assert "--sensitivity-scenario" not in design.argv  # the design study has no such part
    assert design.name == "design" and mine.name == "study"  # their progress lines


def test_two_studies_beside_one_report_need_two_folders(tmp_path, capsys):
    """--with-study is repeatable (make report: default and design, in OUT/study and
    OUT/design); two presets writing one folder are refused before anything runs."""
    assert main(["report", "--out", str(tmp_path), "--with-study", "default",
                 "--with-study", "full"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["treeimpact: error: --with-study full: default writes OUT/study too; "
                   "give one of them"]
    assert not (tmp_path / "study").exists()


def test_your_tree_gets_its_own_band_with_its_measured_inputs_held(tmp_path):
    """A researcher's tree file saying which inputs were measured ([calibration] measured):
    the study's sensitivity part holds them, and the report's answer row for that tree
    carries its own band (one Morris trajectory here: seconds, not the preset's 30)."""
    from dataclasses import replace

    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.analytic.model.scenario_toml import scenario_toml
    from treeimpact.compare.report.validity.sensitivity_study import run_sensitivity
    from treeimpact.compare.report.validity.study import write_study

    tree = replace(load_scenario("open-center"), name="my-tree")
    text = scenario_toml(tree).replace(
        "[calibration]", '[calibration]\nmeasured = ["trunk.clamp_mass", "contact.restitution"]')
    path = tmp_path / "my-tree.toml"
    path.write_text(text)
    study = tmp_path / "study"
    sens = run_sensitivity(study, 1, scenarios=[str(path)], workers=0, sobol=4)
    mine = sens["trees"]["my-tree"]
    assert mine["held"] == {"clamp_mass": 4.0, "restitution": 0.1}
    assert mine["evaluations"] == 5  # one trajectory over the four inputs left
    assert mine["sobol"]["evaluations"] == 24  # Sobol N = 4: 4 x (4 inputs + 2)
    write_study(study, {}, sensitivity=sens)
    for page in ("study.html", "study.md"):  # the study page's Sobol table of this tree
        assert "my-tree (Sobol, 24 evaluations)" in (study / page).read_text()
    paths = write_report(tmp_path / "out", scenarios=[str(path)], study_dirs=[study],
                         runs=RunCache(), engines=())
    (row,) = json.loads(paths["json"].read_text())["answer"]["one_dof"]
    assert row["scenario"] == "my-tree"
    band = row["sensitivity"]["gap.x_max"]
    assert band["evaluations"] == 5 and -1.0 < band["low"] < band["high"] < 10.0
    html = paths["html"].read_text()
    assert "held at the file's measured values: clamp mass 4" in html  # the measure-first line
    # what to measure first for this tree: its four free inputs ranked, in report.json
    first = json.loads(paths["json"].read_text())["answer"]["measure_first"]["my-tree"]
    assert {r["input"] for r in first["rows"]} == {"e_over_g", "log10_pad_duration",
                                                   "root_share", "density"}
    assert set(first["first"]) == {"gap.x_max", "gap.energy_delivered"}
    assert "what to measure first" in html and first["sentence"].startswith("my-tree: ")
