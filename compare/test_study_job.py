"""A study run beside the report (compare/sweep/study_job.py, ``report --with-study``): its
section in the page, its failure as the report's, its end when the report stops."""

from __future__ import annotations

import json
import sys
import time

import pytest

from treeimpact.analytic.errors import ParameterError
from treeimpact.compare.cli import main
from treeimpact.compare.report import write_report
from treeimpact.compare.runs import RunCache
from treeimpact.compare.sweep.study_job import StudyJob


def _quick(job: StudyJob, *grid: str) -> StudyJob:
    """The job running a two-point analytic sweep instead of its preset (seconds, not 30)."""
    job.argv = [sys.executable, "-m", "treeimpact.compare.cli", "sweep", "--scenario",
                "open-center", "--backend", "analytic", "--workers", "0", "--out",
                str(job.out), *(a for g in grid for a in ("--grid", g))]
    return job


def test_a_study_run_beside_the_report_becomes_its_section(tmp_path):
    job = _quick(StudyJob("default", tmp_path / "out" / "study"), "restitution=0.1,0.2")
    paths = write_report(tmp_path / "out", scenarios=["open-center"], runs=RunCache(),
                         engines=(), study_jobs=(job.start(),))
    assert (tmp_path / "out" / "study" / "study.json").exists()
    data = json.loads(paths["json"].read_text())
    assert len(data["studies"]) == 1
    wall = data["runs"]["wall_s"]
    assert wall["study default (a child process, beside all of the above)"] == job.wall_s > 0
    assert "waiting for the studies" in wall


def test_a_failed_study_fails_with_its_exit_code_and_last_line(tmp_path):
    job = _quick(StudyJob("default", tmp_path / "study"), "restitution=2").start()
    with pytest.raises(ParameterError, match=r"--with-study default: .*exit code 2: .*restitution"):
        job.result()


def test_an_unknown_preset_is_refused_before_anything_runs(tmp_path, capsys):
    assert main(["report", "--out", str(tmp_path), "--with-study", "nope"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["treeimpact: error: --with-study 'nope': allowed default, full"]
    assert not (tmp_path / "study").exists()


def test_stopping_the_report_ends_the_study(tmp_path):
    job = StudyJob("default", tmp_path / "study")
    job.argv = [sys.executable, "-c", "import time; time.sleep(60)"]
    job.start()
    t0 = time.perf_counter()
    job.stop()
    assert job._proc.poll() is not None and time.perf_counter() - t0 < 5
