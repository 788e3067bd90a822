"""Bad input and extreme values (issue 12): every case a hostile trial found, as a named
regression. Each ends in exit 0 with plausible numbers, or exit 2 (bad input) / 3 (diverged)
with exactly one line on stderr naming what the user typed; never a traceback or a hang."""

from __future__ import annotations

import json
import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from treeimpact.compare.interface.cli import main
from treeimpact.compare.runs.exits import ExitCode

ROOT = Path(__file__).resolve().parent.parent
SCENARIO = (ROOT / "analytic" / "model" / "scenarios" / "open-center.toml").read_text()


def edited(tmp_path, **fields) -> str:
    """open-center.toml with ``key = value`` lines replaced (first occurrence of each key)."""
    text = SCENARIO
    for key, value in fields.items():
        text, n = re.subn(rf"(?m)^{key}\s*=.*$", f"{key} = {value}", text, count=1)
        assert n == 1, key
    path = tmp_path / "tree.toml"
    path.write_text(text)
    return str(path)


def one_line(capsys, argv, code, *words):
    """Run the CLI in-process; exit ``code`` with one stderr line holding every word."""
    rc = main(argv)
    err = capsys.readouterr().err
    assert rc == code, err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, (w, err)
    return err


@pytest.mark.parametrize("fields, words", [
    ({"damping": "1e12"}, ["trunk.damping = 1000000000000.0", "allowed [0, 1e+06]"]),  # 19.8 GiB
    ({"length": "1e30"}, ["trunk.length"]),  # was ledger 5e55, x_max 0
    ({"density": "1e308"}, ["trunk.density"]),  # was null loss and residual
    ({"density": "1e-3", "clamp_mass": "0", "crown_mass": "0"}, ["trunk.density"]),  # 24 min
    ({"t_end": "1e6"}, ["t_end = 1000000.0 s", "allowed [0.0001, 10] s"]),  # was a hang
], ids=["damping-1e12", "length-1e30", "density-1e308", "light-trunk", "t_end-1e6"])
def test_implausible_scenario_fields_are_refused(tmp_path, capsys, fields, words):
    one_line(capsys, ["simulate", edited(tmp_path, **fields)], 2, *words)


def test_a_pendulum_57_km_long_is_refused_not_simulated(tmp_path, capsys):
    """bullet sdof gave x_max 1.11 where soft and mujoco gave 2.185, ledger 0.30, exit 0."""
    one_line(capsys, ["simulate", edited(tmp_path, equivalent_length="57005"), "--backend",
                      "bullet", "--trunk", "sdof"], 2, "impactor.equivalent_length")


def test_a_steel_stiff_trunk_is_refused(tmp_path, capsys):
    """E = 1e16 Pa on the mujoco SDOF trunk: omega dt = 1.93 was accepted, x_max 2.5x off."""
    path = edited(tmp_path, youngs_modulus="1e16", base_stiffness="1e16")
    one_line(capsys, ["simulate", path, "--backend", "mujoco", "--trunk", "sdof"], 2,
             "trunk.youngs_modulus", "allowed [1e+07, 1e+11] Pa")


def test_the_sdof_trunk_frequency_sets_the_engine_time_step():
    """The stiffest plausible SDOF trunk: its own omega enters the step (omega dt < 2)."""
    from treeimpact.analytic.model.parameters import Trunk
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.mujoco_models._runner import make_setup

    s = load_scenario("open-center")
    stiff = Trunk(length=1.0, clamp_height=0.05, diameter=1.0, density=950.0,
                  youngs_modulus=1e11, clamp_mass=1.0, crown_mass=0.0, damping=0.0,
                  base_stiffness=math.inf)
    import dataclasses

    setup = make_setup(dataclasses.replace(s, trunk=stiff), trunk="sdof")
    omega = math.sqrt(setup.model.equivalent_stiffness / setup.model.dynamic_mass)
    assert omega * setup.dt <= 2 * math.pi / 20 * (1 + 1e-12)  # 20 steps a period


def test_contact_stiffness_1e16_is_refused_before_it_runs(capsys):
    """Was 175 s and 11.5 GB before a MemoryError."""
    one_line(capsys, ["simulate", "open-center", "--backend", "mujoco", "--trunk", "sdof",
                      "--contact-stiffness", "1e16"], 2, "--contact-stiffness", "1e+12")


def test_rk4_with_a_step_too_coarse_for_the_contact_is_refused(capsys):
    """T0 6.09 ms against 2.05 ms with a closed ledger, exit 0: the ledger cannot tell."""
    one_line(capsys, ["simulate", "open-center", "--backend", "mujoco", "--trunk", "sdof",
                      "--integrator", "RK4", "--dt", "1.86e-4"], 2, "--dt", "RK4",
             "rebounds at e = 0.2")


def test_work_budget_is_checked_before_a_run(capsys, monkeypatch):
    monkeypatch.setenv("TREEIMPACT_MAX_STEPS", "1000")
    one_line(capsys, ["simulate", "open-center", "--backend", "mujoco", "--trunk", "sdof"], 2,
             "beyond its budget", "steps > 1e+03 (TREEIMPACT_MAX_STEPS)")


@pytest.mark.parametrize("argv, words", [
    # the 30 m trunk needs a 334-segment chain: 2e5 steps of ~37 ms, ~8000 s (ran past 300 s)
    (["simulate", "{long}", "--backend", "mujoco"], ["beyond its budget", "e+03 s > 120 s",
                                                     "GB > 2 GB (TREEIMPACT_MAX_BYTES)"]),
    (["simulate", "realistic-crown", "--backend", "mujoco", "--segments", "64"],
     ["beyond its budget", "s > 120 s (--max-seconds", "65 degrees of freedom"]),
    (["simulate", "realistic-crown", "--backend", "bullet", "--segments", "100", "--max-seconds",
      "5"], ["beyond its budget", "s > 5 s (--max-seconds", "100 trunk joints"]),
    (["simulate", "{long}", "--backend", "bullet"], ["needs 334 segments", "at most 127"]),
    (["simulate", "central-leader", "--backend", "soft", "--contact-duration", "1e-6"],
     ["beyond its budget", "GB > 2 GB"]),
])
def test_a_run_beyond_its_budget_is_refused_up_front_with_its_estimate(argv, words, capsys,
                                                                         tmp_path):
    long = tmp_path / "long.toml"  # central-leader's trunk 30 m long
    long.write_text(re.sub(r"^length = .*$", "length = 30.0", (
        ROOT / "analytic" / "model" / "scenarios" / "central-leader.toml").read_text(), flags=re.MULTILINE))
    # refused up front: check_work raises before the first step (an admitted run would end
    # with exit 0 after hours, not exit 2 with the estimate); no wall clock read
    one_line(capsys, [a.format(long=long) for a in argv], 2, *words)


def test_max_seconds_admits_a_run_and_long_runs_tell_their_progress(capsys, monkeypatch):
    from treeimpact.analytic import budget

    monkeypatch.setattr(budget, "PROGRESS_AFTER_S", 0.0)  # every run is "long"
    monkeypatch.setattr("treeimpact.compare.runs.progress._on_terminal", lambda stream: True)
    code = main(["simulate", "central-leader", "--backend", "mujoco", "--segments", "4",
                 "--t-end", "0.02", "--max-seconds", "1000", "--json"])
    out, err = capsys.readouterr()
    assert code == 0 and json.loads(out)["backend"] == "mujoco"
    assert "simulate: mujoco (estimated" in err and "step/s" in err  # the bar, its job named
    assert os.environ.get("TREEIMPACT_MAX_SECONDS") is None  # restored after the command
    assert budget._REPORTER is None


@pytest.mark.parametrize("argv, code, words", [
    (["simulate", "open-center", "--backend", "soft", "--t-end", "-1"], 2, ["--t-end = -1.0"]),
    (["simulate", "open-center", "--backend", "mujoco", "--restitution", "1e-308"], 2,
     ["--restitution = 1e-308", "soft contact"]),  # as typed (was a ZeroDivisionError)
    (["report", "--out", "/dev/null/x"], 2, ["--out '/dev/null/x'"]),  # NotADirectoryError
    (["report", "--study", "/nonexistent"], 2, ["--study '/nonexistent'"]),  # after the runs
    (["sweep", "--grid", "restitution=0:1:100000000", "--out", "/tmp/never"], 2,
     ["COUNT"]),  # unbounded
], ids=["soft-t-end-negative", "mujoco-e-1e-308", "report-out-not-a-dir",
        "report-study-missing", "sweep-count-1e8"])
def test_bad_flags_are_one_line(capsys, argv, code, words):
    one_line(capsys, argv, code, *words)


def test_latin1_byte_in_a_scenario_file(tmp_path, capsys):
    path = tmp_path / "tree.toml"
    path.write_bytes(SCENARIO.replace("Table 1", "Table \xe9").encode("latin-1"))
    one_line(capsys, ["simulate", str(path)], 2, "not UTF-8", "offset")


def test_calibration_that_is_not_a_table(tmp_path, capsys):
    path = tmp_path / "tree.toml"
    path.write_text('calibration = "x"\n' + SCENARIO.split("[calibration]")[0])
    one_line(capsys, ["simulate", str(path)], 2, "calibration: expected a table")


def test_results_beyond_the_geometry_or_the_ledger_are_divergences():
    import dataclasses

    from treeimpact.analytic.errors import OutsideValidity, SimulationDiverged
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.analytic.results import check_plausible

    good = simulate(load_scenario("open-center"))
    assert check_plausible(good) is good
    for change, words in (({"x_max": math.nan}, "x_max = nan"),
                          ({"ledger_residual": 0.3}, "ledger residual 0.3"),
                          ({"energy_delivered": 1e6}, "energy_delivered = 1e+06 J beyond"),
                          ({"impact_loss": -50.0}, "the contact created energy"),
                          ({"t_xmax": 1e3}, "t_xmax = 1000 s outside the run")):
        bad = dataclasses.replace(good, metrics={**good.metrics, **change})
        with pytest.raises(SimulationDiverged, match=re.escape(words)) as info:
            check_plausible(bad)
        assert not isinstance(info.value, OutsideValidity), words


def test_a_sound_result_beyond_the_clamp_height_is_outside_validity_not_a_divergence():
    """x_max 2 m on open-center (a = 0.354 m), its ledger and energies sound: was
    SimulationDiverged "x_max = 2.0 m"; now OutsideValidity naming the clamp height and
    the small-deflection trunk of eq 1."""
    import dataclasses

    from treeimpact.analytic.errors import OutsideValidity
    from treeimpact.analytic.impact.simulate import simulate
    from treeimpact.analytic.model.scenario import load_scenario
    from treeimpact.analytic.results import check_plausible

    good = simulate(load_scenario("open-center"))
    bad = dataclasses.replace(good, metrics={**good.metrics, "x_max": 2.0})
    with pytest.raises(OutsideValidity, match=r"x_max = 2 m beyond the clamp height "
                       r"a = 0\.354 m: the small-deflection trunk of eq 1"):
        check_plausible(bad)


def test_mujoco_warnings_go_to_stderr_not_a_log_file_in_the_working_directory(tmp_path):
    code = ("import mujoco\n"
            "from treeimpact.mujoco_models._warnings import mujoco_warnings\n"
            "m = mujoco.MjModel.from_xml_string('<mujoco><option timestep=\"1\"/><worldbody>"
            "<body><joint type=\"slide\" stiffness=\"1e12\"/><geom size=\"0.1\" mass=\"1\"/>"
            "</body></worldbody></mujoco>')\n"
            "d = mujoco.MjData(m); d.qpos[0] = 1\n"
            "with mujoco_warnings():\n"
            "    for _ in range(3): mujoco.mj_step(m, d)\n"
            "assert mujoco.get_mju_user_warning() is None  # MuJoCo's own handler again\n")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                          text=True, env={**os.environ, "PYTHONPATH": str(ROOT)})
    assert proc.returncode == 0 and proc.stdout == ""
    assert proc.stderr.count("mujoco: Nan, Inf or huge value in QACC") == 1  # once per kind
    assert list(tmp_path.iterdir()) == []  # no MUJOCO_LOG.TXT


def test_sigterm_ends_a_sweep_like_ctrl_c(tmp_path):
    out = tmp_path / "sweep"
    proc = subprocess.Popen(
        [sys.executable, "-m", "treeimpact.compare.interface.cli", "sweep", "--grid",
         "restitution=0.1:0.9:300", "--grid", "crown_ratio=0,1,2", "--backend",
         "analytic,soft", "--out", str(out)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60  # a hang guard, not a speed check
    while not (out / "results.csv").exists() and time.monotonic() < deadline:
        time.sleep(0.1)  # running: its journal exists
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().splitlines()[-1].startswith("treeimpact: sweep interrupted")
    assert "Traceback" not in err


def _live(field: int, value: int) -> list[int]:
    """The live (not zombie) processes whose /proc stat ``field`` (after the name; 1: the
    parent's pid, 2: the process group) is ``value`` (Linux /proc)."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[field]) == value and fields[0] != "Z":
            out.append(int(stat.parent.name))
    return out


def _children(pid: int) -> list[int]:
    """The live processes whose parent is ``pid``."""
    return _live(1, pid)


@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGINT])
def test_a_stop_signal_ends_the_report_with_one_line_and_no_orphans(tmp_path, how):
    """`treeimpact report` stopped while its runs are on the pool: exit 130, one line on
    stderr, no traceback, no report page written, and no worker left behind."""
    out = tmp_path / "rep"
    # SIGINT at its default action whatever the test run's (a background job's is ignored,
    # and the report rightly keeps an inherited ignore: test_signals)
    proc = subprocess.Popen(
        [sys.executable, "-c", SIGINT_DEFAULT, "-m", "treeimpact.compare.interface.cli", "report",
         "--out", str(out)],
        cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 60  # a hang guard, not a speed check
    while not _children(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)  # its pool has started
    time.sleep(1.0)
    workers = _children(proc.pid)
    proc.send_signal(how)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert err.strip().count("\n") == 0 and "Traceback" not in err, err
    assert not (out / "report.html").exists()
    time.sleep(0.5)
    assert not [p for p in workers if Path(f"/proc/{p}").exists()
                and "Z" not in Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1][:3]]


def test_a_scheduler_without_workers_is_one_line_after_its_timeout(tmp_path, monkeypatch):
    from distributed import Client, LocalCluster

    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.runs import pool
    from treeimpact.compare.studies.sweep import run

    monkeypatch.setattr(pool, "SCHEDULER_TIMEOUT_S", 1)
    with LocalCluster(n_workers=0, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        with pytest.raises(ParameterError, match=r"no worker joined within 1 s"):
            run.run_sweep("central-leader", ["restitution=0.3"], tmp_path / "s", scheduler=client,
                          identify=False, progress=False)


def test_a_scheduler_lost_during_the_sweep_is_one_line_and_keeps_the_rows(tmp_path,
                                                                          monkeypatch):
    """The connection dropping while results come back (distributed's CommClosedError is an
    OSError): one line naming the scheduler, no traceback."""
    import distributed
    from distributed import Client, LocalCluster
    from distributed.comm.core import CommClosedError

    from treeimpact.analytic.errors import ParameterError
    from treeimpact.compare.studies.sweep import run

    def lost(futures, *a, **k):
        raise CommClosedError("in <TCP (closed)>: Stream is closed")
        yield  # pragma: no cover - a generator, as as_completed is iterated

    monkeypatch.setattr(distributed, "as_completed", lost)
    with LocalCluster(n_workers=1, processes=False, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        with pytest.raises(ParameterError, match=r"lost the scheduler \(CommClosedError: "):
            run.run_sweep("central-leader", ["restitution=0.3"], tmp_path / "s", scheduler=client,
                          identify=False, progress=False)


def test_a_library_warning_during_a_command_is_one_stderr_line(capsys):
    import warnings

    from treeimpact.compare.interface import process

    before = warnings.showwarning
    restore = process.install_budget(None)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("always")
            warnings.warn_explicit("overflow encountered\n  in multiply", RuntimeWarning,
                                   "/x/chain.py", 205)
    finally:
        process.restore_budget(restore)
    err = capsys.readouterr().err
    assert err == ("treeimpact: warning: overflow encountered in multiply (RuntimeWarning, "
                   "chain.py:205)\n")
    assert warnings.showwarning is before


IDENTIFY = ["--impactor-mass", "132.4", "--equivalent-length", "1.51",
            "--release-angle-deg", "36.39",
            "--clamp-height", "0.315", "--diameter", "0.126"]


def _record(path, x) -> str:
    path.write_text("t [s],x [m]\n" + "".join(f"{i / 5000},{v}\n" for i, v in enumerate(x)))
    return str(path)


@pytest.mark.parametrize(("flag", "words"), [
    ("out.xyz", ["--plot 'out.xyz': allowed a file ending in .png, .pdf, .svg"]),
    ("{dir}", ["is a directory: name a file in it"])])
def test_identify_plot_paths_are_checked_before_the_fit(flag, words, tmp_path, capsys):
    rec = _record(tmp_path / "r.csv", [0.0] * 100 + [0.001] * 500)
    one_line(capsys, ["identify", rec, *IDENTIFY, "--plot", flag.format(dir=tmp_path)], 2,
             *words)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]  # nothing written


def test_identify_refuses_a_fifo_and_a_record_beyond_its_size(tmp_path, capsys, monkeypatch):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    one_line(capsys, ["identify", str(fifo), *IDENTIFY], 2, "not a regular file")  # no wait
    from treeimpact.analytic.identify import pendulum_record

    monkeypatch.setattr(pendulum_record, "MAX_SAMPLES", 500)
    rec = _record(tmp_path / "r.csv", [0.0] * 600)
    one_line(capsys, ["identify", rec, *IDENTIFY], 2, "600 samples; allowed up to 500")


def test_identify_json_stdout_holds_only_json_when_lapack_complains(tmp_path, capfd):
    """A record that is zero but one sample: LAPACK prints its argument errors on fd 1."""
    rec = _record(tmp_path / "r.csv", [0.01 if i == 300 else 0.0 for i in range(600)])
    code = main(["identify", rec, *IDENTIFY, "--json"])
    out, _ = capfd.readouterr()
    data = json.loads(out)  # only JSON on stdout
    assert not data["explained"] and data["verdict"].endswith("not fitted; declare the units")
    assert code == ExitCode.NOT_ACHIEVED  # not fitted: was 0
    assert not any(v["determined"] for v in data["fit"].values())  # nothing "determined"


#: When a report of one scenario is stopped (issue 35: one SIGINT in 22 was swallowed):
#: (what is awaited, seconds after it), each an event every report has on any machine and
#: with any cache (progress is not: it is drawn on a terminal only):
#: the command runs (its --out folder exists; imports follow), its first pool's workers
#: exist, its sweeps have started (their journals), its sections' figures are drawn while
#: the record fits run on a pool. Measured here: 0.1, 5, 9 and 16 s into a 60 s report.
SIGINT_MOMENTS = [("command", 0.0), ("command", 1.0), ("pool", 0.0), ("pool", 1.0),
                  ("sweeps", 0.2), ("figures", 0.2)]
#: Hang guards, not speed checks: seconds for the awaited event (a loaded machine) and for
#: the exit after the SIGINT (a pool's workers are ended within 2 * pool.END_WORKERS_S).
AWAIT_S, EXIT_S = 120, 30


def _reached(awaited: str, out: Path, pid: int) -> bool:
    if awaited == "command":
        return out.is_dir()
    if awaited == "pool":
        return bool(_children(pid))
    if awaited == "sweeps":
        return any((out / "sweeps").glob("*/sweep.json"))
    return any(out.glob(".report-new-*/figures/small-e.png"))  # drawn into the new set


def _group(pgid: int) -> list[int]:
    """The live processes of process group ``pgid``."""
    return _live(2, pgid)


#: Runs the rest of its argv with SIGINT at its default action, whatever the test run's
#: (CI runs it as a background job, where SIGINT is ignored, and the report rightly keeps
#: an inherited ignore); exec keeps the pid.
SIGINT_DEFAULT = ("import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
                  "os.execv(sys.executable, [sys.executable, *sys.argv[1:]])")


@pytest.mark.slow
@pytest.mark.parametrize("awaited, delay", SIGINT_MOMENTS,
                         ids=[f"{a}+{d}s" for a, d in SIGINT_MOMENTS])
def test_ctrl_c_ends_the_report_with_exit_130_at_any_moment(tmp_path, awaited, delay):
    """SIGINT at each phase of `treeimpact report`: exit 130, its one line, no traceback
    (a KeyboardInterrupt that lands in a callback is delivered again, not printed and lost),
    no process of its group left; never a hang (its whole group is killed in the end)."""
    import threading

    out = tmp_path / "rep"
    proc = subprocess.Popen(
        [sys.executable, "-c", SIGINT_DEFAULT, "-m", "treeimpact.compare.interface.cli", "report",
         "--scenario", "open-center", "--out", str(out)], cwd=ROOT, stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE, text=True, start_new_session=True)
    lines: list = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stderr.readline, "")),
                              daemon=True)
    reader.start()
    try:
        deadline = time.monotonic() + AWAIT_S  # a hang guard, not a speed check
        while proc.poll() is None and time.monotonic() < deadline and not _reached(
                awaited, out, proc.pid):
            time.sleep(0.02)
        assert proc.poll() is None, f"the report ended before {awaited!r}: {lines[-3:]}"
        assert _reached(awaited, out, proc.pid), f"no {awaited!r} within {AWAIT_S} s"
        time.sleep(delay)
        assert proc.poll() is None, f"the report ended before its SIGINT: {lines[-3:]}"
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=EXIT_S)
        except subprocess.TimeoutExpired:
            pytest.fail(f"still running {EXIT_S} s after SIGINT: {''.join(lines)[-500:]}")
        reader.join(timeout=10)
        err = "".join(lines)
        assert proc.returncode == 130, err[-500:]
        assert "Traceback" not in err and "Exception ignored" not in err, err[-800:]
        assert err.strip().splitlines()[-1].startswith("treeimpact: interrupted"), err[-300:]
        # a resource tracker ends at its pipe's EOF; a hang guard, not a speed check: a
        # process still there after 60 s is left behind
        deadline = time.monotonic() + 60
        while _group(proc.pid) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not _group(proc.pid), "processes left behind"
    finally:
        try:
            os.killpg(proc.pid, signal.SIGKILL)  # the report and all it started
        except ProcessLookupError:
            pass
        proc.wait(timeout=10)


def test_an_interrupt_python_could_only_print_is_delivered_again(capsys):
    """The swallowed SIGINT of issue 35: a KeyboardInterrupt raised in a weakref callback is
    printed as 'Exception ignored' and lost, and the command went on to exit 0. Under the
    command's stop signals it is the stop request it was: exit 130, one line."""
    import weakref

    from treeimpact.compare.interface.process import run_command, stop_signals

    class Thing:
        pass

    def interrupt(_):
        raise KeyboardInterrupt

    def command(_):
        thing = Thing()
        ref = weakref.ref(thing, interrupt)  # noqa: F841 - its callback runs at the del
        del thing
        for _ in range(2000):  # the re-delivered interrupt lands here, between bytecodes
            time.sleep(0.001)
        return 0

    with stop_signals():
        code = run_command(command, None)
    err = capsys.readouterr().err
    assert code == 130, err
    assert err.startswith("treeimpact: interrupted") and err.count("\n") == 1, err


# --------------------------------------------------------------------------- issue 35, item 2
# Bad input is exit 2 naming the flag or field, never exit 3 with an exception's name.


@pytest.mark.parametrize("argv, words", [
    (["contact", "--mass", "1e-300", "--restitution", "0.5", "--touch-duration", "1e-3",
      "--dt", "1e-5"], ["--mass = 1e-300 kg is out of range: allowed [1e-06, 1e+09] kg"]),
    (["simulate", "open-center", "--backend", "bullet", "--dt", "1e-300"],
     ["beyond its budget", "dt 1e-300 s"]),  # was "diverged: ZeroDivisionError"
    (["simulate", "open-center", "--backend", "mujoco", "--dt", "1e-300"],
     ["beyond its budget", "dt 1e-300 s"]),
], ids=["contact-mass-1e-300", "bullet-dt-1e-300", "mujoco-dt-1e-300"])
def test_extreme_numbers_are_bad_input_not_a_divergence(capsys, argv, words):
    one_line(capsys, argv, 2, *words)


def test_an_integer_of_400_digits_in_a_scenario_file_is_bad_input(tmp_path, capsys):
    """Was "simulation diverged: OverflowError (int too large to convert to float)"."""
    path = edited(tmp_path, mass="1" + "0" * 400)
    one_line(capsys, ["simulate", path], 2, "impactor.mass: a number of 401 digits")


SCENARIO_FLAGS = {"--clamp-height": "0.315", "--diameter": "0.126", "--impactor-mass": "132.4",
                  "--equivalent-length": "1.51", "--release-angle-deg": "36.39",
                  "--youngs-modulus": "9e9", "--dynamic-mass": "110", "--a1": "1.167",
                  "--a2": "-34.817", "--equivalent-stiffness": "1.5e6"}


def _scenario_argv(**changes) -> list:
    flags = SCENARIO_FLAGS | {f"--{k.replace('_', '-')}": v for k, v in changes.items()}
    return [a for kv in flags.items() for a in kv]


@pytest.mark.parametrize("change", [{"equivalent_stiffness": "180"},
                                    {"equivalent_stiffness": "360"},
                                    {"equivalent_stiffness": "10000"}, {"impactor_mass": "10000"}],
                         ids=["K_T-180", "K_T-360", "K_T-1e4", "m-1e4"])
def test_scenario_writes_only_files_that_run(tmp_path, capsys, change):
    """Each exited 0 with t_end = 0.1 s, and `simulate` then refused the file it wrote."""
    assert main(["scenario", "t", *_scenario_argv(**change), "--out", str(tmp_path)]) == 0
    capsys.readouterr()
    assert main(["simulate", str(tmp_path / "t.toml"), "--json"]) == 0, \
        capsys.readouterr().err


def test_scenario_refuses_a_given_t_end_its_tree_outlasts(tmp_path, capsys):
    one_line(capsys, ["scenario", "t", *_scenario_argv(t_end="0.001")], 2,
             "--t-end = 0.001 s is too short")


@pytest.mark.parametrize("change, words", [
    ({"a1": "1e300", "x_max": "0.01", "tau": "0.1"},
     ["--a1 = 1e+300 m/s is out of range: allowed (0, 100] m/s"]),
    ({"a1": "1.167", "x_max": "0.01", "tau": "1e300"},
     ["--tau = 1e+300 s is out of range: allowed (0, 10] s"]),
    ({"a1": "1e-300", "x_max": "0.01", "tau": "0.1"},
     ["--a1 = 1e-300 m/s", "b tau = 3.48e+300", "an overdamped motion"]),
    ({"a1": "1.167", "x_max": "0.5", "tau": "0.1"},
     ["--x-max = 0.5 m is out of range: allowed (0, 0.315] m"]),
], ids=["a1-1e300", "tau-1e300", "a1-1e-300", "x_max-beyond-a"])
def test_regression_inputs_beyond_double_precision_are_bad_input(capsys, change, words):
    """Each was exit 3 "simulation diverged: OverflowError" (e^(b tau) overflowed), or a file
    written from an x_max beyond the clamp height; now exit 2 naming the flag."""
    argv = _scenario_argv(a2="-34.8", **change)
    i = argv.index("--equivalent-stiffness")
    one_line(capsys, ["scenario", "t", *argv[:i], *argv[i + 2:]], 2, *words)


def test_a_tree_the_small_deflection_model_cannot_hold_is_outside_validity(capsys):
    """A 10,000 kg pendulum at 60 deg on a thin trunk: the analytic x_max 0.344 m exceeds
    a = 0.315 m; was exit 3 "simulation diverged"; now exit 4 worded as the model's
    validity, the clamp height named."""
    argv = _scenario_argv(diameter="0.05", impactor_mass="10000", release_angle_deg="60",
                          dynamic_mass="20", equivalent_stiffness="300")
    i = argv.index("--a1")
    err = one_line(capsys, ["scenario", "t", *argv[:i], *argv[i + 4:], "--damping-rate",
                            "1"], ExitCode.NOT_ACHIEVED, "outside the model's validity: ",
                   "x_max = 0.3444 m beyond the clamp height a = 0.315 m")
    assert "diverged" not in err


@pytest.mark.parametrize("argv, words", [
    (["simulate", "open-center", "--rate", "1"], ["--rate: only with --record"]),
    (["simulate", "open-center", "--noise", "-5"], ["--noise: only with --record"]),
    (["simulate", "open-center", "--seed", "3"], ["--seed: only with --record"]),
    (["report", "--with-study", "", "--out", "/tmp/never"],
     ["--with-study '': allowed default, full"]),
])
def test_a_flag_that_would_be_ignored_is_refused(capsys, argv, words):
    one_line(capsys, argv, 2, *words)


@pytest.mark.parametrize("value", ["0", "1"])
def test_segments_has_one_allowed_range(capsys, value):
    """--segments 0 said [1, 1000] and --segments 1 [2, 1000]."""
    one_line(capsys, ["simulate", "open-center", "--backend", "mujoco", "--segments", value], 2,
             f"--segments = {value} is out of range: allowed [2, 1000]")


def test_a_chain_beyond_the_budget_is_refused_before_its_model_is_built(capsys, monkeypatch):
    """`--segments 1000` took 7.8 s (a 1000-segment MJCF compiled) to refuse, silent."""
    from treeimpact.mujoco_models import _builder

    def never(*a, **k):
        raise AssertionError("the model was built")

    monkeypatch.setattr(_builder, "build_spec", never)
    one_line(capsys, ["simulate", "open-center", "--backend", "mujoco", "--segments", "1000"],
             2, "beyond its budget", "1001 degrees of freedom")


def test_a_mujoco_warning_is_worded_and_a_diverged_run_carries_it_in_its_one_line(capsys):
    """MuJoCo's "Nan, Inf or huge value in QACC" line preceded the exit-3 message."""
    from treeimpact.analytic.errors import SimulationDiverged
    from treeimpact.mujoco_models import _runner, _warnings

    seen = ["Nan, Inf or huge value in QACC at DOF 0. The simulation is unstable. Time = 0.01."]
    out = _runner._with_warnings([SimulationDiverged("mujoco: non-finite state")], seen)
    assert str(out[0]) == f"mujoco: non-finite state (MuJoCo warned: {seen[0]})"
    assert capsys.readouterr().err == ""  # nothing on its own line before the exit-3 one
    _warnings._WARNED.discard("Some kind of warning.")
    _runner._with_warnings([object()], ["Some kind of warning. Time = 0.1."])
    assert capsys.readouterr().err == ("treeimpact: warning: mujoco: Some kind of warning. "
                                       "Time = 0.1.\n")


def test_a_row_wider_than_the_header_is_refused_not_a_pandas_warning(tmp_path, capsys):
    """The first data row's extra value made pandas warn (ParserWarning) and drop data."""
    rows = ["t [s],x [m]", "0,0,5"] + [f"{i / 5000},{0.001 * (i > 50)}" for i in range(1, 600)]
    path = tmp_path / "r.csv"
    path.write_text("\n".join(rows) + "\n")
    one_line(capsys, ["identify", str(path), *IDENTIFY], 2, "every row needs 2 values at row 2")


def test_degenerate_record_says_only_treeimpact_lines(tmp_path, capfd):
    """The record zero but one sample is refused before any fit (no chattering sequence to
    read): stderr holds treeimpact's own warnings, then its one not-achieved line."""
    rec = _record(tmp_path / "r.csv", [0.01 if i == 300 else 0.0 for i in range(600)])
    assert main(["identify", rec, *IDENTIFY, "--json"]) == ExitCode.NOT_ACHIEVED  # units
    _, err = capfd.readouterr()
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert lines[-1].startswith("treeimpact: not achieved: the record was not fitted"), err
    assert all(ln.startswith("treeimpact: warning: ") for ln in lines[:-1]), err


def test_lapack_s_own_lines_reach_the_terminal_worded(capfd):
    """LAPACK's " ** On entry to DLASCL parameter number 4" lines (a least-squares solve of
    NaNs, as identify's fits could meet) come out as treeimpact's worded warnings."""
    import numpy as np

    from treeimpact.compare.runs.backends import worded_c_output

    with worded_c_output("LAPACK", "the caller checks its own results"):
        with pytest.raises(np.linalg.LinAlgError):
            np.linalg.lstsq(np.full((5, 3), np.nan), np.ones(5), rcond=None)
    out, err = capfd.readouterr()
    assert out == ""
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert lines and all(ln.startswith("treeimpact: warning: LAPACK: ") for ln in lines), err
    assert any("On entry to DLASCL" in ln for ln in lines), err


# ------------------------------------------------------------------------------------------
# issue 35 (identify says only what the record supports): one case of each class the
# independent fuzzer found; the validation set (tests/data/identify) holds more of each.

def _identify_json(capsys, path, *flags) -> dict:
    """identify --json's output; exit 0 for a record fitted, 4 (one stderr line) for one
    not fitted."""
    code = main(["identify", str(path), *IDENTIFY, *flags, "--json"])
    out, err = capsys.readouterr()
    data = json.loads(out)
    fitted = "not fitted" not in data["verdict"]
    assert code == (ExitCode.OK if fitted else ExitCode.NOT_ACHIEVED), err
    assert fitted or err.startswith("treeimpact: not achieved: the record was not fitted")
    return data


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_identify_refuses_a_record_of_noise_alone(seed, tmp_path, capsys):
    """1 mm of Gaussian noise, 600 samples at 5 kHz, no impact: was "explained
    (noise-limited)" in one seed of four, M_T "determined" in [0.12, 48264] kg; now not
    explained, no tree quantity determined (the noise judged apart from the fit)."""
    import numpy as np

    x = 1e-3 * np.random.default_rng([seed, 35]).standard_normal(600)
    data = _identify_json(capsys, _record(tmp_path / "noise.csv", x))
    assert data["explained"] is False and data["verdict"].startswith("NOT explained (")
    assert {d["kind"] for d in data["diagnoses"]} & {"no-impact", "units"}
    assert not any(data["fit"][k]["determined"] for k in ("M_T", "K_T", "C_T", "omega_1"))


def _make_records():
    """The validation set's generator (tests/data/identify/make_records.py)."""
    import sys

    sys.path.insert(0, str(ROOT / "tests" / "data" / "identify"))
    import make_records

    return make_records


def test_identify_fixes_nothing_from_a_record_that_ends_at_the_impact(tmp_path, capsys):
    """A record whose last sample is one into the impact: omega_1 was "determined" at
    0.031 rad/s in [0, null]; now nothing of the tree is determined and it is not
    explained."""
    mr = _make_records()
    tree = mr.TREES["D"]
    t, x, _, t_c = mr.sdof_record(tree, 5000.0, 0.01, 1)
    t, x = mr.defect("ends-at-impact", t, x, tree, t_c, None)
    data = _identify_json(capsys, _record(tmp_path / "ends.csv", x))
    assert data["explained"] is False
    for k in ("M_T", "K_T", "C_T", "omega_1", "V_1", "restitution"):
        q = data["fit"][k]
        assert not q["determined"] and q["value"] is None, (k, q)


def test_a_record_that_ends_at_the_impact_is_not_called_a_unit_error():
    """Cut one sample into the impact, a record has no measured trunk speed (its rise is
    within one sample): the trunk-speed bound (M_PLAUSIBLE) said "x looks like mm" on 11 of
    the full validation set's 40 such records (tree D at 5 kHz, seeds 11-15 among them);
    it is not judged on a speed it does not have. A record in cm declared as m still is."""
    from treeimpact.analytic.identify.record_features import features, unit_suspicions

    mr = _make_records()
    tree = mr.TREES["D"]
    for seed in (11, 13, 14, 15):
        t, x, _, t_c = mr.sdof_record(tree, 5000.0, 0.01, seed)
        cut_t, cut_x = mr.defect("ends-at-impact", t, x, tree, t_c, None)
        feat = features(cut_t, cut_x)
        assert not feat.velocity_resolved, seed
        assert unit_suspicions(feat, 1.0, impactor_mass=132.4) == [], seed
        whole = features(t, x)  # the same record whole: resolved, and cm caught
        assert whole.velocity_resolved and unit_suspicions(whole, 1.0, impactor_mass=132.4) == []
        in_cm = features(t, 100.0 * x)
        assert unit_suspicions(in_cm, 1.0, impactor_mass=132.4)[0].startswith("x looks like cm")


def test_identify_explains_the_record_from_the_impact_to_the_separation(tmp_path, capsys):
    """Tree D, 5 kHz, 1 % noise, from the impact to the pendulum's separation (27 ms): was
    "NOT explained (optimiser)", M_T -19 % with a drift fitted that so short a record
    cannot tell from the motion; now the offset and drift are held at 0 and said so, and
    M_T and K_T are within 2 %."""
    mr = _make_records()
    tree = mr.TREES["D"]
    t, x, _ = mr.short_record(tree, 5000.0, 0.01, 1)
    data = _identify_json(capsys, _record(tmp_path / "short.csv", x))
    assert data["explained"] is True and data["verdict"] == "explained"
    assert data["held"] == {"x_offset": "held at 0", "x_drift": "held at 0",
                            "x_drift2": "held at 0"}
    for k in data["held"]:  # were "determined": true beside the table's "held at 0"
        assert data["fit"][k]["held"] == "held at 0" and data["fit"][k]["determined"] is False
    assert data["fit"]["M_T"]["held"] is None and data["fit"]["M_T"]["determined"] is True
    assert "sensor-held" in {d["kind"] for d in data["diagnoses"]}
    for k, v in (("M_T", tree.M_T), ("K_T", tree.K_T)):
        assert abs(data["fit"][k]["value"] / v - 1.0) < 0.02, (k, data["fit"][k])


def test_identify_names_both_columns_of_an_undeclared_ms_mm_record(capsys):
    """t in ms and x in mm, declared as neither: was "implausible in any unit"; now one
    warning line naming both and how to declare them, the record not fitted."""
    spec = ROOT / "tests" / "data" / "identify" / "files" / "undeclared-ms-mm.csv"
    flags = ["--impactor-mass", "100", "--equivalent-length", "1.5", "--release-angle-deg", "35",
             "--clamp-height", "0.45", "--diameter", "0.15"]  # tree B's pendulum and clamp
    assert main(["identify", str(spec), *flags]) == ExitCode.NOT_ACHIEVED  # was 0
    captured = capsys.readouterr()
    assert captured.err.count("\n") == 1
    assert captured.err.startswith("treeimpact: not achieved: the record was not fitted: ")
    assert "t looks like ms and x like mm, not s and m" in captured.err
    assert "--time-unit ms --length-unit mm" in captured.err
    assert "NOT explained (units)" in captured.out
    assert main(["identify", str(spec), *flags, "--json"]) == ExitCode.NOT_ACHIEVED
    captured = capsys.readouterr()
    assert json.loads(captured.out)["verdict"].startswith("NOT explained (units)")
    assert captured.err.count("\n") == 1 and "--time-unit ms" in captured.err
    assert main(["identify", str(spec), *flags, "--time-unit", "ms", "--length-unit",
                 "mm"]) == ExitCode.OK, capsys.readouterr().err  # the flags it names


def test_identify_given_restitution_is_its_own_interval(tmp_path, capsys):
    """--restitution 0.5 printed e = 0.5 in [0.5000000000000001, 0.5000000000000001]; a held
    parameter's interval is its value, exactly, and the text says "given"."""
    mr = _make_records()
    t, x, _, _ = mr.sdof_record(mr.TREES["D"], 5000.0, 0.01, 1)
    path = _record(tmp_path / "r.csv", x)
    data = _identify_json(capsys, path, "--restitution", "0.5")
    e = data["fit"]["restitution"]
    assert (e["value"], e["low"], e["high"]) == (0.5, 0.5, 0.5) and e["determined"]
    assert data["held"]["restitution"] == "given"


def test_identify_constant_pendulum_column_is_one_line_naming_it(tmp_path, capsys):
    """A y column that never changes: was a traceback (ValueError: array must not contain
    infs or NaNs); now exit 2, one line naming the column as typed."""
    path = tmp_path / "r.csv"
    path.write_text("t [s],x [m],pendulum (mm)\n" + "".join(
        f"{i / 5000},{0.0 if i < 100 else 1e-5 * (i - 100)},3.5\n" for i in range(600)))
    one_line(capsys, ["identify", str(path), *IDENTIFY], 2, "column 'pendulum (mm)' never "
             "changes", "the pendulum's column holds no motion")


def test_simulate_s_removed_spelling_names_its_new_flag(capsys):
    """Issue 41: `simulate --damping` was refused without naming --trunk-damping-model."""
    one_line(capsys, ["simulate", "open-center", "--damping", "joint"], 2,
             "--damping was renamed: did you mean --trunk-damping-model?")
