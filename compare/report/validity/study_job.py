"""A model-validity study run beside other work: ``treeimpact sweep --preset NAME --out DIR``
in a child process with its own worker pool, so that ``treeimpact report --with-study NAME``
makes the report's own runs, fits and figures while the study runs (on 2 cores neither
leaves a core idle while it draws its figures alone). The program the child runs is its
caller's to name (the command line sits above this floor: docs/architecture.md). Design
notes: docs/report.md."""

from __future__ import annotations

import os
import subprocess
import threading
import time
from pathlib import Path

from treeimpact.analytic.errors import NotAchieved, ParameterError, SimulationDiverged
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.model.scenario import shipped_scenarios
from treeimpact.analytic.model.scenario_toml import scenario_toml

from ...runs.exits import ExitCode
from ...runs.pool import POLL_S, check_stop
from ...runs.progress import RECORD, RELAY_ENV, Relay
from .study import PRESETS

#: Seconds a stopped study has to end its workers after SIGTERM before it is killed.
STOP_GRACE_S = 10.0


class StudyJob:
    """The study of preset ``preset`` into ``out``, started by :meth:`start`; :meth:`result`
    waits for it (its directory), :meth:`stop` ends it. Its progress is drawn in this
    process's display (compare.runs.progress.Relay) and its other lines go to this process's
    stderr as it prints them, each after "study: "."""

    def __init__(self, preset: str, out, program, scenarios=None):
        """``program``: the command line of the ``treeimpact`` program (a list of str, e.g.
        ``[sys.executable, "-m", NAME]``), which runs ``sweep --preset``; ``scenarios``: the
        report's trees (shipped names, TOML paths or Scenarios), the trees of the study's
        sensitivity part (default: every shipped one), the first of them the tree of its
        maps, speed and identification parts (default: the preset's); a Scenario object is
        written into ``out/scenarios/`` for the child to read."""
        if preset not in PRESETS:  # a one-line error before anything starts
            raise ParameterError(f"--with-study {preset!r}: allowed {', '.join(PRESETS)}")
        self.preset, self.out = preset, Path(out)
        self.name = PRESETS[preset].folder  # its progress line's
        self.argv = [*program, "sweep", "--preset", preset, "--out", str(self.out)]
        sources = [self._source(s) for s in scenarios or ()]
        if sources:  # the maps, speed and identification parts: the report's first tree
            self.argv += ["--scenario", sources[0]]
        for source in sources if PRESETS[preset].sensitivity else ():
            self.argv += ["--sensitivity-scenario", source]
        self._proc = None
        self._relay = None
        self._last = ""
        self.wall_s = None  # s, from start to its end

    def _source(self, scenario) -> str:
        """A scenario as the child's command line names it: a shipped name, an absolute
        path, or a file written for it from a Scenario object."""
        if isinstance(scenario, Scenario):
            folder = self.out / "scenarios"
            folder.mkdir(parents=True, exist_ok=True)
            path = folder / f"{scenario.name}.toml"
            path.write_text(scenario_toml(scenario), encoding="utf-8")
            return str(path.resolve())
        text = str(scenario)
        return text if text in shipped_scenarios() else str(Path(text).resolve())

    def start(self) -> "StudyJob":
        """Start the child process (``treeimpact sweep --preset``), its output relayed by a
        thread; returns the job."""
        self._t0 = time.perf_counter()
        env = os.environ | {RELAY_ENV: self.name}  # its progress as records for this display
        self._proc = subprocess.Popen(self.argv, stdout=subprocess.PIPE, env=env,
                                      stderr=subprocess.STDOUT, text=True, bufsize=1)
        self._relay = threading.Thread(target=self._pass_on, daemon=True)
        self._relay.start()
        return self

    def _pass_on(self) -> None:
        relay = Relay(self.name)
        try:
            for line in self._proc.stdout:
                relay.line(line)
                if line.strip() and not line.startswith(RECORD):
                    self._last = line.strip()
        finally:
            relay.abandon()

    def result(self) -> Path:
        """Wait for the study (looking at the stop request every POLL_S s); its directory,
        or its failure as this command's: bad input, a divergence, an interruption."""
        while self._proc.poll() is None:
            check_stop()
            time.sleep(POLL_S)
        self._relay.join()
        self.wall_s = time.perf_counter() - self._t0
        code = self._proc.returncode
        if code == ExitCode.OK:
            return self.out
        what = f"the study (treeimpact sweep --preset {self.preset}) ended with exit code " \
               f"{code}: {self._last}"
        if code == ExitCode.INTERRUPTED:
            raise KeyboardInterrupt
        if code == ExitCode.DIVERGED:
            raise SimulationDiverged(what)
        if code == ExitCode.NOT_ACHIEVED:  # it ran, and says what it could not do
            raise NotAchieved(f"--with-study {self.preset}: {what}")
        raise ParameterError(f"--with-study {self.preset}: {what}")

    def check(self) -> None:
        """Raise now if the study has already failed (as :meth:`result`), so a report does
        not finish its own work for a page it cannot write; nothing if it runs or passed."""
        if self._proc is not None and self._proc.poll() not in (None, ExitCode.OK):
            self.result()

    def stop(self) -> None:
        """End the study if it still runs: SIGTERM (it stops its workers), then a kill."""
        if self._proc is None or self._proc.poll() is not None:
            return
        self._proc.terminate()
        try:
            self._proc.wait(STOP_GRACE_S)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
