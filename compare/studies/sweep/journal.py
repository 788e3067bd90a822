"""A sweep's files: its journal (``results.csv``, one flushed line per finished row, so that
a killed sweep resumes where it stopped), its table (``results.parquet``, written at the end)
and its spec (``sweep.json``, refused when a resumed directory holds another sweep), each
read back with a one-line error when it is not what a sweep writes.

Design notes and measured figures: docs/sweeps.md.
"""

from __future__ import annotations

import csv
import csv as csv_module
import json
import math
from pathlib import Path

from treeimpact.analytic.errors import ParameterError
from treeimpact.analytic.metrics import METRIC_KEYS
from treeimpact.analytic.model.parameters import Scenario
from treeimpact.analytic.results import json_text
from treeimpact.compare.runs.cache import OK

from .execute import IDENT_KEYS, MODEL_KEYS, load_analysis
from .grid import Grid, point_key

JOURNAL = "results.csv"
TABLE = "results.parquet"
SPEC = "sweep.json"
BASE_COLUMNS = ("scenario", "point", "target", "backend", "kind", "previous", "status", "error",
                "wall_s", "t_end", "task", "worker", "finished")


def columns_for(grid: Grid, analysis: str | None = None) -> list[str]:
    """The table's columns: the run's, the grid's axes, then the metrics, model and the
    identification (the standard analysis) or the columns ``analysis`` declares."""
    if analysis is not None:
        return list(BASE_COLUMNS) + list(grid.names) + list(load_analysis(analysis).columns)
    return (list(BASE_COLUMNS) + list(grid.names) + list(METRIC_KEYS)
            + [f"model.{k}" for k in MODEL_KEYS] + [f"id.{k}" for k in IDENT_KEYS]
            + [f"truth.{k}" for k in IDENT_KEYS] + ["id_error"])


def _header(path: Path):
    with open(path, newline="", encoding="utf-8") as fh:
        return next(csv.reader(fh), None)


def read_file(path: Path, reader, what: str):
    """``reader(path)`` of a file a sweep wrote and reads back (its journal, table, spec), or
    a one-line ParameterError naming it when it is not what the sweep wrote: corrupt,
    another encoding, nested beyond reason, a field longer than a CSV reader takes."""
    # lazy: +194 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    try:
        return reader(path)
    except (ValueError, UnicodeDecodeError, RecursionError, csv_module.Error,
            pd.errors.ParserError, pd.errors.EmptyDataError, OSError) as exc:
        detail = str(exc).strip().splitlines()[0][:120] if str(exc).strip() else \
            type(exc).__name__
        raise ParameterError(f"--out {str(path.parent)!r}: {path.name} is not the {what} a "
                             f"sweep writes ({type(exc).__name__}: {detail}); move it away "
                             "or use a new --out") from None


class Journal:
    """The CSV table at ``path``, appended one flushed line per row with the ``columns``
    (column names, in order) as its header: a new file gets the header, an existing one
    loses an unfinished last line and is refused (one-line ParameterError) when its
    header is not ``columns``."""

    def __init__(self, path: Path, columns: list[str]):
        self.path = Path(path)
        self.columns = columns
        fresh = not self.path.exists() or self.path.stat().st_size == 0
        if not fresh:
            drop_partial_line(self.path)
            header = read_file(self.path, _header, "table")
            if header != columns:
                raise ParameterError(f"--out {self.path.parent}: {self.path.name} has other "
                                     f"columns (another grid); use a new --out")
        self.fh = open(self.path, "a", newline="")
        self.writer = csv.writer(self.fh)
        if fresh:
            self.writer.writerow(columns)
            self.fh.flush()

    def append(self, rows: list[dict]) -> None:
        """Write ``rows`` (dicts by column) as one flushed line each."""
        for r in rows:
            self.writer.writerow([_cell(r.get(c)) for c in self.columns])
        self.fh.flush()

    def close(self) -> None:
        """Close the file."""
        self.fh.close()


def _cell(v):
    """One journal cell's text: None and NaN empty, a float by its repr (exact), a text on
    one line; a numpy scalar as its Python value (a float32 NaN was written "nan")."""
    if v is None:
        return ""
    if hasattr(v, "item") and not isinstance(v, str):  # numpy's bool_, integer, floating
        v = v.item()
    if isinstance(v, float):
        return "" if math.isnan(v) else repr(v)
    if isinstance(v, str):
        return " ".join(v.split())  # one line per row, always
    return v


def drop_partial_line(path: Path) -> None:
    """Cut, in the file at ``path``, a last line left unfinished by a killed sweep (it was
    never a finished row); a file ending in a newline is left as it is."""
    with open(path, "rb+") as fh:
        data = fh.read()
        if data.endswith(b"\n"):
            return
        fh.truncate(data.rfind(b"\n") + 1)


def read_table(out, *, dedupe: bool = True, grid: Grid | None = None):
    """The rows of the sweep in the directory ``out`` as a pandas DataFrame, from its
    journal, else its table (last row per (point, target) when ``dedupe``; only the points
    of ``grid`` when given: a directory resumed with other values keeps the earlier rows in
    its journal); a one-line ParameterError when there is neither."""
    # lazy: +194 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    out = Path(out)
    journal = out / JOURNAL
    if journal.exists():
        drop_partial_line(journal)
        df = read_file(journal, lambda p: pd.read_csv(p, keep_default_na=True), "table")
    elif (out / TABLE).exists():
        df = read_file(out / TABLE, pd.read_parquet, "table")
    else:
        raise ParameterError(f"--out {out}: no sweep table ({JOURNAL} or {TABLE}) there")
    if dedupe and len(df):
        df = df.drop_duplicates(subset=["point", "target"], keep="last").reset_index(drop=True)
    if grid is not None and len(df):
        df = df[df["point"].isin({point_key(p) for p in grid.points()})].reset_index(drop=True)
    return df


def write_parquet(out) -> Path:
    """The deduplicated table of the sweep in ``out`` written as ``results.parquet`` (text
    columns as strings); returns its path."""
    out = Path(out)
    df = read_table(out)
    for c in df.columns:  # Parquet needs one type per column: text columns stay text
        if df[c].dtype == object:
            df[c] = df[c].astype("string")
    path = out / TABLE
    df.to_parquet(path, index=False)
    return path


def make_out(out) -> Path:
    """The output directory, created; a one-line ``--out`` error when it cannot be."""
    out = Path(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError(f"--out {str(out)!r}: cannot create the directory "
                             f"({exc.strerror or type(exc).__name__}); allowed: a new or "
                             f"existing writable directory") from None
    return out


def spec_of(scenario: Scenario, grid: Grid, identify: bool, analysis: str | None) -> dict:
    """What defines a sweep (``sweep.json``), as a dict: its ``scenario`` (as its
    ``to_dict``), ``grid`` (its specs and axes), whether it runs the paper's identification
    (``identify``) and its ``analysis`` (``module:function`` or None)."""
    return {"version": 1, "scenario": scenario.to_dict(), "grid": grid.specs(),
            "axes": list(grid.names), "identify": identify, "analysis": analysis}


def check_spec(out: Path, spec: dict) -> None:
    """Refuse (one-line ParameterError) a directory ``out`` that holds a sweep with another
    scenario, axes, identification or analysis than ``spec``; nothing for a new one."""
    path = out / SPEC
    if not path.exists():
        return
    old = read_file(path, lambda p: json.loads(p.read_text(encoding="utf-8")), "spec")
    if not isinstance(old, dict):
        raise ParameterError(f"--out {str(out)!r}: {SPEC} is not the spec a sweep writes; "
                             "move it away or use a new --out")
    for key in ("scenario", "axes", "identify", "analysis"):
        if json_text(old.get(key), sort_keys=True) != json_text(spec[key], sort_keys=True):
            raise ParameterError(f"--out {out}: holds a sweep with another {key} "
                                 f"({SPEC}); use a new --out to start a different sweep")



def finished(journal_path: Path, retry_failed: bool = False) -> set:
    """The (point, target) pairs an earlier run of the sweep finished, read from its
    journal at ``journal_path`` (its last row of each; only those that succeeded when
    ``retry_failed``); empty for a new sweep."""
    if not (journal_path.exists() and journal_path.stat().st_size):
        return set()
    # lazy: +194 ms at import otherwise (pandas, numpy, pyarrow),
    # which this module's other callers do not need
    import pandas as pd

    drop_partial_line(journal_path)
    prev = read_file(journal_path, lambda p: pd.read_csv(
        p, usecols=["point", "target", "status"]), "table")
    prev = prev.drop_duplicates(subset=["point", "target"], keep="last")
    if retry_failed:
        prev = prev[prev["status"] == OK]
    return set(zip(prev["point"], prev["target"]))
