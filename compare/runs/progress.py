"""Progress of long commands on stderr: one display for the whole command, one line per job
("report", and "study" for the study a report runs beside it), drawn by tqdm only when
stderr is a terminal. A job that planned its stages shows its overall fraction of them and
the time left, with its active stages' counts; else its one active stage's bar. A child job
sends its progress to its parent as records, which the parent draws on the job's line."""

from __future__ import annotations

import itertools
import os
import sys
import threading
import time

#: The environment variable a parent sets for a child job: the job's name. The child then
#: writes its progress as :data:`RECORD` lines on stderr, for :class:`Relay` to draw.
RELAY_ENV = "TREEIMPACT_PROGRESS_RELAY"
#: How a progress record starts: ``RECORD<id>\t<event>\t<desc>\t<unit>\t<done>\t<total>``.
RECORD = "treeimpact-progress\t"
#: Seconds between two records of one stage (its opening and closing are always sent).
RECORD_EVERY_S = 0.2
_LOCK = threading.RLock()
_IDS = itertools.count(1)
_CURRENT = {"job": ""}  # a library caller's: no name


def _on_terminal(stream) -> bool:
    return bool(getattr(stream, "isatty", lambda: False)())


class _Job:
    """One job's line on ``stream``: its ``planned`` stages (None: not planned), its open
    stages (:class:`Progress`) and each stage's fraction done; ``percent`` of the plan."""

    def __init__(self, name: str, stream):
        self.name, self.stream, self.planned, self.bar = name, stream, None, None
        self.open: dict = {}
        self.fractions: dict = {}
        self.percent = 0.0
        self.drawn = _on_terminal(stream)  # or a stage asked for a bar anywhere

    def _draw(self, total, desc, unit, fmt=None):
        if self.bar is not None:
            self.bar.close()
        kw = {"bar_format": fmt} if fmt else {}
        # lazy: +128 ms at import otherwise (tqdm; load 13 on 2 cores), which only a drawn bar
        # needs: every command imports this module, `treeimpact --help` draws none
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=desc, unit=unit, file=self.stream, **kw)

    def refresh(self, stage=None, closed: bool = False) -> None:
        """Redraw after ``stage`` (a Progress opened, updated or ``closed``: then done)."""
        if stage is not None:
            self.fractions[stage.id] = (stage.done / stage.total if stage.total and not closed
                                        else 1.0)
        if self.planned:
            self.percent = 100.0 * min(1.0, sum(self.fractions.values()) / self.planned)
        if not self.drawn:
            return
        active = ", ".join(f"{p.desc} {p.done}/{p.total} {p.unit}s" for p in self.open.values())
        if self.planned:
            if self.bar is None:
                self._draw(100, f"{self.name}: overall", "%", "{desc} {percentage:3.0f} % of "
                           f"{self.planned} stages" + "|{bar}| {elapsed}, about {remaining} "
                           "left{postfix}")
            self.bar.set_postfix_str(active, refresh=False)
            self.bar.update(self.percent - self.bar.n)
        elif stage is not None and stage.id in self.open:
            desc = f"{self.name}: {stage.desc}" if self.name else stage.desc
            if self.bar is None or self.bar.desc != desc:
                self._draw(stage.total, desc, stage.unit)
            self.bar.update(stage.done - self.bar.n)

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
            self.bar = None


_JOBS: dict[str, _Job] = {}


def _job(name: str, stream) -> _Job:
    """Job ``name``, drawn on ``stream`` unless it is drawing elsewhere now."""
    with _LOCK:
        job = _JOBS.setdefault(name, _Job(name, stream))
        if not job.open and job.bar is None and job.stream is not stream:
            job.stream, job.drawn = stream, _on_terminal(stream)
        return job


def set_job(name: str) -> None:
    """Name this process's job (``name``: the command, "report"); a child job's name comes
    from :data:`RELAY_ENV`."""
    _CURRENT["job"] = os.environ.get(RELAY_ENV) or name


def plan(stages: int, stream=None) -> None:
    """This process's job runs ``stages`` progress stages: its line counts them equally (on
    ``stream``, default stderr, when a terminal; in a child job, a record for the parent)."""
    stream = stream or sys.stderr
    if os.environ.get(RELAY_ENV):
        print(f"{RECORD}0\tplan\t\t\t0\t{stages}", file=stream, flush=True)
    else:
        set_job_plan(_CURRENT["job"], stages, stream)


def set_job_plan(name: str, stages: int, stream=None) -> None:
    """Job ``name`` (this process's or a child's) runs ``stages`` stages; drawn on ``stream``
    (default stderr) when a terminal."""
    with _LOCK:
        job = _job(name, stream or sys.stderr)
        job.planned = stages
        job.close()  # redrawn as the overall line
        job.refresh()


def end_open_bars() -> None:
    """End every job's line where it stands, so that a message printed next (an error,
    "interrupted") starts a line of its own."""
    with _LOCK:
        for job in _JOBS.values():
            job.close()


def finish() -> None:
    """The command's end: every line ended, the jobs forgotten."""
    end_open_bars()
    with _LOCK:
        _JOBS.clear()


def write(line: str, stream=None) -> None:
    """``line`` on stderr (``stream``), above the jobs' lines when they are drawn."""
    stream = stream or sys.stderr
    if any(job.bar is not None for job in _JOBS.values()):
        # lazy: a bar is drawn (above), so tqdm is imported already
        from tqdm import tqdm

        with _LOCK:
            tqdm.write(line.rstrip("\n"), file=stream)
    else:
        stream.write(line if line.endswith("\n") else line + "\n")
        stream.flush()


class Progress:
    """One stage of a job: counts finished items of ``total``; ``update(n)`` after each,
    ``close()`` at the end. ``desc``: the stage's name; ``unit``: what an item is ("run",
    "step"); ``stream``: where it is drawn (default stderr; nothing unless a terminal);
    ``job``: the job it belongs to (default this process's, :func:`set_job`; in a child
    job, records for the parent instead); ``bar``: True draws on any stream, False
    nowhere, None on a terminal only."""

    def __init__(self, total: int, desc: str, unit: str = "run", stream=None,
                 job: str | None = None, bar: bool | None = None):
        self.total, self.desc, self.unit = total, desc, unit
        self.stream = stream if stream is not None else sys.stderr
        self.done, self.id, self._sent = 0, next(_IDS), 0.0
        self._relay = job is None and bar is None and bool(os.environ.get(RELAY_ENV))
        self._job = None
        if self._relay:
            self._record("open")
        else:
            self._job = _job(job or _CURRENT["job"], self.stream)
            with _LOCK:
                if bar is not None:
                    self._job.drawn = bar
                self._job.open[self.id] = self
                self._job.refresh(self)

    def _record(self, event: str) -> None:
        self._sent = time.perf_counter()
        print(f"{RECORD}{self.id}\t{event}\t{self.desc}\t{self.unit}\t{self.done}\t"
              f"{self.total}", file=self.stream, flush=True)

    def update(self, n: int = 1) -> None:
        """``n`` more items finished."""
        self.done += n
        if self._relay:
            if time.perf_counter() - self._sent >= RECORD_EVERY_S:
                self._record("update")
            return
        with _LOCK:
            self._job.refresh(self)

    def close(self) -> None:
        """The stage's end (all its items counted as they were)."""
        if self._relay:
            self._record("close")
            return
        with _LOCK:
            self._job.open.pop(self.id, None)
            self._job.refresh(self, closed=True)
            if not self._job.open and (not self._job.planned or self._job.percent >= 100.0):
                self._job.close()  # nothing left to draw: the line ends before what follows

    def abandon(self) -> None:
        """A stage that failed or was stopped: its job's line ended where it stands."""
        if self._job is not None:
            with _LOCK:
                self._job.open.pop(self.id, None)
                self._job.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


class Relay:
    """The parent's side of a child job ``job`` (its stderr read line by line): progress
    records drawn on the job's line in this process's display (``stream``, default stderr;
    nothing when it is not a terminal), every other line written above it, after the
    job's name."""

    def __init__(self, job: str, stream=None):
        self.job, self.stream, self.stages = job, stream or sys.stderr, {}

    def line(self, line: str) -> None:
        """One line the child printed."""
        if not line.startswith(RECORD):
            if line.strip():
                write(f"{self.job}: {line.rstrip()}", self.stream)
            return
        ident, event, desc, unit, done, total = line[len(RECORD):].rstrip("\n").split("\t")
        if event == "plan":
            set_job_plan(self.job, int(total), self.stream)
            return
        stage = self.stages.get(ident)
        if stage is None:
            stage = self.stages[ident] = Progress(int(total), desc, unit, self.stream,
                                                  job=self.job)
        if int(done) > stage.done:
            stage.update(int(done) - stage.done)
        if event == "close":
            stage.close()
            del self.stages[ident]

    def abandon(self) -> None:
        """The child ended: the stages it left open ended where they stand."""
        for stage in self.stages.values():
            stage.abandon()
        self.stages.clear()
