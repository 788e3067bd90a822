"""A pendulum-test record as a user brings it: time, the trunk's displacement at the clamp
and optionally the pendulum's, read from a CSV file as spreadsheets and loggers write them
(a BOM, ',' ';' tab or space between values, decimal commas, comment lines, columns in any
order among others, units in the header), converted to SI and checked on reading (one-line
errors naming the file, row and column)."""

from __future__ import annotations

import csv
import io
import re
import warnings
from dataclasses import dataclass, field
from decimal import Decimal, InvalidOperation
from pathlib import Path

import numpy as np

from treeimpact.analytic.errors import ParameterError

MIN_SAMPLES = 20
#: Column names (case-insensitive) of each channel; a unit may follow in brackets.
NAMES = {"t": ("t", "time"), "x": ("x", "trunk", "displacement", "x_trunk"),
         "y": ("y", "pendulum", "y_pendulum")}
#: Units and their power of ten (converted in decimal, exactly, then rounded once).
TIME_UNITS = {"s": 0, "ms": -3, "us": -6}
LENGTH_UNITS = {"m": 0, "cm": -2, "mm": -3, "um": -6}
_MICRO = {"µs": "us", "μs": "us", "µm": "um", "μm": "um", "sec": "s", "msec": "ms"}
#: The largest |value| of a column (SI) and its unit: no pendulum test comes near in any unit
#: the reader knows (a 30 m displacement read as um is 3e7; a 1e6-sample record's span in
#: us read as s ~1e7 s, an epoch clock in s 1.7e9 s), and the record's arithmetic (squares,
#: differences, sums over MAX_SAMPLES) stays far from overflow below it.
MAGNITUDE = {"t": (1e12, "s"), "x": (1e9, "m"), "y": (1e9, "m")}
COMMENT = ("#", "%", "//")  # a line starting with one of these (after blanks) is a comment


@dataclass(frozen=True)
class Record:
    """A displacement record (SI), checked on construction (ParameterError naming the row).

    Attributes:
        t: the sample times, increasing, s.
        x: the trunk's displacement at the clamp, m.
        y: the pendulum's displacement in the trunk's frame (y = x in contact), m, or None.
        time_unit: the unit the times were given in (converted to s here).
        length_unit: the unit the displacements were given in (converted to m here).
        y_unit: the unit of y where its header names another (None: ``length_unit``).
        rows: each sample's line in its file (for messages), or None.
        warnings: one line each (columns ignored, times made relative).
        t_start: the first time as given, s.
        source: where it came from (a file's name), for messages.
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray | None = None
    time_unit: str = "s"
    length_unit: str = "m"
    rows: np.ndarray | None = None
    warnings: tuple = ()
    t_start: float = 0.0
    source: str = field(default="", compare=False)
    y_unit: str | None = None  # the unit y was given in (None: length_unit's)

    def row(self, i: int) -> int:
        """The file line of sample i (its position + 2 for a record without a file)."""
        return int(self.rows[i]) if self.rows is not None else i + 2

    def _check_magnitude(self, where: str, name: str, v: np.ndarray) -> None:
        """ParameterError naming column ``name`` and the first row of ``v`` beyond
        :data:`MAGNITUDE` (checked before any arithmetic on the record: 1.7e308 overflowed
        in the record's own checks and printed numpy's warnings)."""
        limit, unit = MAGNITUDE[name]
        big = np.flatnonzero(np.abs(v) > limit)
        if big.size:
            i = int(big[0])
            raise ParameterError(f"{where}: {name} = {v[i]:.3g} {unit} at row {self.row(i)} is "
                                 f"out of range: allowed |{name}| <= {limit:g} {unit}")

    def __post_init__(self):
        t, x = np.asarray(self.t, float), np.asarray(self.x, float)
        where = f"record {self.source!r}" if self.source else "record"
        if t.ndim != 1 or t.shape != x.shape:
            raise ParameterError(f"{where}: t and x must be columns of the same length")
        if t.size < MIN_SAMPLES:
            raise ParameterError(f"{where}: {t.size} samples; at least {MIN_SAMPLES} needed")
        for name, v in (("t", t), ("x", x)) + ((("y", np.asarray(self.y, float)),)
                                               if self.y is not None else ()):
            bad = np.flatnonzero(~np.isfinite(v))
            if bad.size:
                raise ParameterError(f"{where}: {name} is not a finite number at row "
                                     f"{self.row(int(bad[0]))}")
            self._check_magnitude(where, name, v)
        steps = np.diff(t)
        if np.any(steps <= 0):
            i = int(np.flatnonzero(steps <= 0)[0]) + 1
            raise ParameterError(f"{where}: time t does not increase at row {self.row(i)} "
                                 "(sorted, without repeats, is required)")
        if not np.max(x) > np.min(x):  # compared, not subtracted: no overflow
            raise ParameterError(f"{where}: x never changes: the record holds no impact")
        if self.y is not None and not np.max(self.y) > np.min(self.y):
            raise ParameterError(f"{where}: y never changes: the pendulum's column holds no "
                                 "motion (leave it out, or record the pendulum)")

#: The largest record read: its samples (a 1 s test at 1 MHz) and its file's size, so that
#: a fit stays within seconds and ~1 GB (a fit of 1e5 samples: ~1 s, benchmarks/bench_identify.py).
MAX_SAMPLES = 1_000_000
MAX_RECORD_BYTES = 64_000_000

def parse_column(text: str) -> tuple[str, str | None]:
    """('t' | 'x' | 'y' | the name as given, unit or None) of a header cell's ``text`` such
    as ``t [ms]``, ``x (mm)``, ``time/s`` or ``Displacement [µm]``."""
    cell = text.strip().strip('"').strip()
    m = re.fullmatch(r"(.*?)\s*(?:\[([^\]]*)\]|\(([^)]*)\)|/\s*([A-Za-zµμ]+))", cell)
    name, unit = (m.group(1), next(u for u in m.groups()[1:] if u is not None)) if m else (
        cell, None)
    key = name.strip().lower().replace(" ", "_")
    for channel, names in NAMES.items():
        if key in names:
            key = channel
            break
    else:
        key = name.strip()
    if unit is not None:
        unit = _MICRO.get(unit.strip(), unit.strip()).lower()
    return key, unit


def read_record(path, *, time_unit: str | None = None, length_unit: str | None = None
                ) -> Record:
    """A :class:`Record` from the CSV file at ``path``: a header naming the columns ``t``
    (or ``time``),
    ``x`` (``trunk``, ``displacement``) and optionally ``y`` (``pendulum``), in any order
    among other columns (ignored, said so), each with an optional unit in brackets (t: s,
    ms, us; x, y: m, cm, mm, um); ``time_unit``/``length_unit`` give the units of columns
    without one (default s and m; a header's unit that disagrees is an error). Comment
    lines (#, %, //) and blank lines are skipped; a UTF-8 BOM, ';', tab or space
    separators and decimal commas are recognised. Times are made relative to the first
    sample (exactly, in decimal: epoch times keep their sub-millisecond digits)."""
    name = str(Path(path))
    lines = _lines(Path(path))
    sep, decimal = _dialect([ln for _, ln in lines[:50]])
    cells = _split(lines[0][1], sep)
    keys = _header(name, lines[0], cells, decimal)
    units = _units(name, cells, time_unit, length_unit)
    data = _table([ln for _, ln in lines[1:]], sep, len(cells), name, [i for i, _ in lines[1:]])
    rows = np.array([i for i, _ in lines[1:]], int)
    power = {"t": TIME_UNITS[units["t"]], "x": LENGTH_UNITS[units["x"]],
             "y": LENGTH_UNITS[units["y"]]}
    values = {}
    for j, key in enumerate(keys):
        if key in ("t", "x", "y"):  # in decimal where a unit is converted: one rounding
            values[key] = _numbers(data[j], decimal, name, cells[j].strip(), rows,
                                   exact=key == "t" or power[key] != 0)
    ignored = [c.strip() for c, k in zip(cells, keys) if k not in ("t", "x", "y")]
    warnings = [f"record {name!r}: columns ignored: {', '.join(ignored)}"] if ignored else []
    t0 = values["t"][0] if values["t"] else Decimal(0)
    t = np.array([float((v - t0).scaleb(power["t"])) for v in values["t"]], float)
    t_start = float(t0.scaleb(power["t"]))
    if abs(t_start) > 60.0:
        warnings.append(f"record {name!r}: times made relative to the first sample (t = "
                        f"{t0} {units['t']} there, like a clock's)")
    x, y = (None if key not in values else np.array(
        [float(v.scaleb(power[key])) if power[key] else v for v in values[key]], float)
        for key in ("x", "y"))
    for key, v in (("x", x), ("y", y)):  # the column as typed in the message
        if v is not None and v.size and np.all(np.isfinite(v)) and not np.max(v) > np.min(v):
            what = ("the record holds no impact" if key == "x" else "the pendulum's column "
                    "holds no motion (leave it out, or record the pendulum)")
            raise ParameterError(f"record {name!r}: column {cells[keys.index(key)].strip()!r}"
                                 f" never changes: {what}")
    return Record(t, x, y, time_unit=units["t"], length_unit=units["x"], rows=rows,
                  warnings=tuple(warnings), t_start=t_start, source=name, y_unit=units["y"])


def _lines(path: Path) -> list:
    """[(line number, text)] of the file's header and data lines (comments and blank lines
    left out): a regular file, at most MAX_RECORD_BYTES and MAX_SAMPLES lines, UTF-8 (a BOM
    too) or a spreadsheet's ANSI export."""
    name = str(path)
    try:
        if path.exists() and not path.is_file():  # a FIFO or a device would block or not end
            raise ParameterError(f"record {name!r}: not a regular file")
        if path.exists() and path.stat().st_size > MAX_RECORD_BYTES:
            raise ParameterError(
                f"record {name!r}: {path.stat().st_size / 1e6:.3g} MB; allowed up to "
                f"{MAX_RECORD_BYTES / 1e6:.3g} MB (a pendulum test needs 0.1-1 s at 1-50 kHz: "
                "cut the record or decimate it)")
        raw = path.read_bytes()
    except OSError as exc:
        raise ParameterError(f"record {name!r}: cannot be read ({exc.strerror or exc})"
                             ) from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")  # a spreadsheet's ANSI export
    lines = [(i + 1, ln) for i, ln in enumerate(text.splitlines())
             if ln.strip() and not ln.lstrip().startswith(COMMENT)]
    if not lines:
        raise ParameterError(f"record {name!r}: empty file (no header, no data)")
    if len(lines) - 1 > MAX_SAMPLES:
        raise ParameterError(f"record {name!r}: {len(lines) - 1} samples; allowed up to "
                             f"{MAX_SAMPLES} (a pendulum test needs 0.1-1 s at 1-50 kHz: "
                             "cut the record or decimate it)")
    return lines


def _header(name: str, line: tuple, cells: list, decimal: str) -> list:
    """The channel of each header cell ('t', 'x', 'y' or the name as given): a header of
    names, one t and one x, at most one y."""
    header_line, header = line
    keys = [parse_column(c)[0] for c in cells]
    if all(_is_number(c, decimal) for c in cells):
        raise ParameterError(f"record {name!r}: line {header_line} is numbers, not a header; "
                             "the first line must name the columns (t, x and optionally y, "
                             "units in brackets: 't [s],x [mm]')")
    for ch in ("t", "x"):
        if keys.count(ch) != 1:
            raise ParameterError(
                f"record {name!r}: header {header.strip()!r} has {keys.count(ch)} column(s) "
                f"{ch}; allowed: one each of t (or time) and x (or trunk, displacement), "
                f"y (or pendulum) optional, units in brackets (t: s, ms, us; x, y: m, cm, "
                f"mm, um)")
    if keys.count("y") > 1:
        raise ParameterError(f"record {name!r}: header {header.strip()!r} has more than one y")
    return keys


def _units(name: str, cells: list, time_unit: str | None, length_unit: str | None) -> dict:
    """The unit of each channel: its header's, else the flag's, else s and m; a header's
    unit the flag contradicts, or one not allowed, is an error."""
    units = {"t": time_unit, "x": length_unit, "y": length_unit}
    for cell in cells:
        key, unit = parse_column(cell)
        if key not in units or unit is None:
            continue
        allowed = TIME_UNITS if key == "t" else LENGTH_UNITS
        if unit not in allowed:
            raise ParameterError(f"record {name!r}: column {cell.strip()!r}: unit {unit!r}; "
                                 f"allowed {', '.join(allowed)}")
        flag = time_unit if key == "t" else length_unit
        if flag is not None and flag != unit:
            raise ParameterError(f"record {name!r}: column {cell.strip()!r} is in {unit}, "
                                 f"but --{'time' if key == 't' else 'length'}-unit says {flag}")
        units[key] = unit
    units = {k: (v or ("s" if k == "t" else "m")) for k, v in units.items()}
    for key, allowed in (("t", TIME_UNITS), ("x", LENGTH_UNITS)):
        if units[key] not in allowed:
            raise ParameterError(f"--{'time' if key == 't' else 'length'}-unit "
                                 f"{units[key]!r}: allowed {', '.join(allowed)}")
    return units


def _dialect(sample: list[str]) -> tuple[str, str]:
    """(separator, decimal mark) of the lines: csv.Sniffer among ',', ';', tab, '|' and
    blanks; a decimal comma where the separator is not ',' and numbers hold ','."""
    joined = "\n".join(sample)
    try:
        sep = csv.Sniffer().sniff(joined, delimiters=",;\t|").delimiter
    except csv.Error:
        sep = None
    if sep is None or all(len(_split(ln, sep)) < 2 for ln in sample):
        sep = " " if all(len(ln.split()) >= 2 for ln in sample) else ","
    if sep == "," and all(ln.count(";") >= 1 for ln in sample):
        sep = ";"
    decimal = "," if sep != "," and any(re.search(r"\d,\d", ln) for ln in sample[1:]) else "."
    return sep, decimal


def _split(line: str, sep: str) -> list[str]:
    return line.split() if sep == " " else next(csv.reader([line], delimiter=sep))


def _table(lines: list[str], sep: str, width: int, name: str, numbers: list[int]) -> list:
    """The columns (lists of str) of the data lines, by pandas' C reader."""
    # lazy: +345 ms at import otherwise (pandas)
    import pandas as pd

    if not lines:
        return [[] for _ in range(width)]
    text = "\n".join(" ".join(ln.split()) if sep == " " else ln for ln in lines)

    try:
        with warnings.catch_warnings():  # a row wider than the header: dropped data, refused
            warnings.simplefilter("error", pd.errors.ParserWarning)
            frame = pd.read_csv(io.StringIO(text), sep=sep, header=None, dtype=str,
                                keep_default_na=False, skipinitialspace=True,
                                names=range(width), index_col=False)
    except pd.errors.ParserWarning:
        i = next((i for i, ln in enumerate(lines) if len(_split(ln, sep)) != width), 0)
        raise ParameterError(f"record {name!r}: every row needs {width} values at row "
                             f"{numbers[i]}") from None
    except (pd.errors.ParserError, ValueError) as exc:
        found = re.search(r"line (\d+)", str(exc))
        where = f" at row {numbers[int(found.group(1)) - 1]}" if found and int(
            found.group(1)) <= len(numbers) else ""
        raise ParameterError(f"record {name!r}: every row needs {width} values{where}"
                             ) from None
    if len(frame) != len(lines):  # pragma: no cover - a line pandas merged or split
        raise ParameterError(f"record {name!r}: rows could not be read one by one")
    return [frame[j].tolist() for j in range(width)]


def _is_number(cell: str, decimal: str) -> bool:
    try:
        float(cell.strip().replace(decimal, ".") if decimal == "," else cell.strip())
    except ValueError:
        return False
    return True


def _numbers(cells: list, decimal: str, name: str, column: str, rows, *,
             exact: bool = False) -> list:
    """The column's numbers (Decimal when ``exact``, else float): a missing or non-numeric
    cell is an error naming its row and column."""
    out = []
    for i, cell in enumerate(cells):
        c = cell.strip().strip('"') if isinstance(cell, str) else ""
        if decimal == ",":
            c = c.replace(",", ".")
        if not c:
            raise ParameterError(f"record {name!r}: row {rows[i]} has no value in column "
                                 f"{column!r}")
        try:
            v = Decimal(c) if exact else float(c)
            if exact and not v.is_finite():
                raise InvalidOperation
        except (ValueError, InvalidOperation):
            if not exact and c.lower() in ("nan", "inf", "-inf"):
                out.append(float(c))
                continue
            raise ParameterError(f"record {name!r}: row {rows[i]}, column {column!r}: "
                                 f"{cell.strip()!r} is not a number") from None
        out.append(v)
    return out
