"""Every JSON the package writes goes through one converter (analytic.results.to_jsonable,
written by json_text with allow_nan=False): numpy scalars and arrays, enums, dataclasses
and paths become JSON, NaN and inf become null, and no NaN or Infinity token is ever
written (issue 54: ``identify --json`` crashed on a numpy bool, ``restitution=1`` wrote a
JSON NaN). Each ``--json`` command is run on the records the tests generate and parsed
with a strict parser."""

from __future__ import annotations

import ast
import dataclasses
import enum
import functools
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from treeimpact.analytic.results import json_text, to_jsonable
from treeimpact.compare.interface.cli import main
from treeimpact.compare.runs.exits import ExitCode

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "identify"
sys.path.insert(0, str(DATA))
import make_records as mr  # noqa: E402 - the validation set's generator, from its folder

META = json.loads((DATA / "cases.json").read_text())
#: The issue's pendulum test (the central-leader tree's), as identify's flags.
TEST = ["--impactor-mass", "132.4", "--equivalent-length", "1.51", "--release-angle-deg",
        "36.39", "--clamp-height", "0.315", "--diameter", "0.126"]


def _no_constant(name):
    raise ValueError(f"not strict JSON: {name}")


def strict(text: str):
    """``text`` parsed as strict JSON: NaN, Infinity and -Infinity refused."""
    return json.loads(text, parse_constant=_no_constant)


def _cli_json(capsys, argv, codes=(ExitCode.OK,)):
    """The strict-parsed stdout of the command line ``argv`` (with --json), its exit code
    one of ``codes``."""
    code = main([*argv, "--json"])
    out, err = capsys.readouterr()
    assert code in codes, (argv, code, err)
    return strict(out)


class _Kind(enum.Enum):
    A = "a-kind"


@dataclasses.dataclass(frozen=True)
class _Pair:
    low: float
    high: np.float32


def test_the_converter_takes_numpy_scalars_arrays_enums_dataclasses_and_paths():
    """Each type to its JSON form, written out by hand; non-finite values to null."""
    data = {"b": np.bool_(True), "i": np.int64(7), "u": np.uint8(3), "f": np.float32(0.5),
            "nan": np.float64("nan"), "inf": -math.inf, "a": np.array([[1, 2], [3, 4]]),
            "ab": np.array([True, False]), "af": np.array([np.nan, 1.5]),
            "kind": _Kind.A, "pair": _Pair(1.0, np.float32(np.inf)), "path": Path("x/y.csv"),
            "t": (np.int32(1), "s", None), 2: "int key", _Kind.A: "enum key"}
    assert strict(json_text(data)) == {
        "b": True, "i": 7, "u": 3, "f": 0.5, "nan": None, "inf": None,
        "a": [[1, 2], [3, 4]], "ab": [True, False], "af": [None, 1.5], "kind": "a-kind",
        "pair": {"low": 1.0, "high": None}, "path": "x/y.csv", "t": [1, "s", None],
        "2": "int key", "a-kind": "enum key"}
    assert type(to_jsonable(np.bool_(False))) is bool  # json.dumps refuses numpy's bool
    with pytest.raises(TypeError, match="object has no JSON form"):
        json_text({"x": object()})


def test_no_package_writer_bypasses_the_converter():
    """Every json.dump(s) in the installed package is json_text's own or a key (a stable
    text to compare or hash, where inf must stay distinct from None): no writer of its
    own that could write NaN or crash on a numpy scalar."""
    keys = {("analytic", "results.py"),  # json_text itself
            ("analytic/model", "scenario_toml.py"),  # a TOML basic string's quoting
            ("compare/runs", "cache.py"), ("compare/runs", "provenance.py"),  # scenario digests
            ("compare/studies/sweep", "grid.py"),  # grid keys
            ("compare/studies/sweep", "plan.py"),  # task keys
            ("compare/studies/sweep", "execute.py")}  # one analysis per distinct record: a key
    found = set()
    for top in ("analytic", "compare", "mujoco_models", "bullet_models"):
        for path in (ROOT / top).rglob("*.py"):
            if "tests" in path.relative_to(ROOT).parts:
                continue
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if (isinstance(node, ast.Attribute) and node.attr in ("dump", "dumps")
                        and isinstance(node.value, ast.Name) and node.value.id == "json"):
                    found.add((path.parent.relative_to(ROOT).as_posix(), path.name))
    assert found <= keys, sorted(found - keys)
    assert ("analytic", "results.py") in found  # the search sees json_text's own call


def _write(path: Path, t, x, y=None) -> str:
    cols = [t, x] + ([y] if y is not None else [])
    head = "t [s],x [m]" + (",y [m]" if y is not None else "")
    path.write_text(head + "\n" + "".join(",".join(repr(float(v)) for v in row) + "\n"
                                          for row in zip(*cols)))
    return str(path)


def _flags(f: dict) -> list[str]:
    return ["--impactor-mass", str(f["mass"]), "--equivalent-length",
            str(f["equivalent_length"]), "--release-angle-deg", str(f["release_angle_deg"]),
            "--clamp-height", str(f["clamp_height"]), "--diameter", str(f["diameter"])]


def _check_identify(data: dict) -> None:
    """identify --json's layout holds on any record: every quantity's determined a JSON
    boolean (numpy's was the crash), values a number or null."""
    assert isinstance(data["explained"], bool)
    for name, q in data["fit"].items():
        assert isinstance(q["determined"], bool), name
        assert q["value"] is None or isinstance(q["value"], (int, float)), name


#: One record of each family of the validation set (tests/data/identify, make_records.py):
#: the three trees clean and noisy at 500 Hz (A: the issue's M_T = 40 kg tree at 2 %), the
#: pendulum's y, each defect, a flexible trunk, noise alone, a record ending at the impact,
#: one from the impact to the separation.
FAMILIES = ["A-500Hz-2%-s1", "B-500Hz-clean", "C-500Hz-5%-s1", "C-500Hz-2%-y-s1",
            "B-2000Hz-1%-drift1-s1", "B-2000Hz-1%-bend10-s1", "B-2000Hz-1%-spike-s1",
            "B-2000Hz-1%-truncated-s1", "beam-crown3-2000Hz-1%", "noise-only-s1",
            "A-2000Hz-1%-ends-at-impact-s1", "D-5000Hz-1%-to-separation-s1"]


@functools.cache
def _cases() -> dict:
    """The FAMILIES' cases with their arrays (a plain cache, not a module fixture: the
    test scheduler's groups, conftest.py, stay as they are)."""
    return {c["id"]: c for c in mr.load(DATA) if c["id"] in FAMILIES}


@pytest.mark.parametrize("case_id", FAMILIES)
def test_identify_json_on_every_record_family(case_id, tmp_path, capsys):
    c = _cases()[case_id]
    path = _write(tmp_path / "r.csv", c["t"], c["x"], c["y"])
    data = _cli_json(capsys, ["identify", path, *_flags(c["flags"])],
                     codes=(ExitCode.OK, ExitCode.NOT_ACHIEVED))
    _check_identify(data)
    if case_id == "A-500Hz-2%-s1":  # e given: held, its interval its value
        data = _cli_json(capsys, ["identify", path, *_flags(c["flags"]), "--restitution",
                                  "0.3"])
        _check_identify(data)
        assert data["fit"]["restitution"]["held"] == "given"


@pytest.mark.parametrize("name", sorted(META["files"]))
def test_identify_json_on_every_file_format(name, capsys):
    """The formats (BOM, semicolons, tabs, an epoch clock) and the undeclared units (not
    fitted: exit 4, the JSON still written)."""
    tree = META["files"][name].get("tree")
    flags = META["tree_flags"][tree] if tree else META["file_flags"]
    data = _cli_json(capsys, ["identify", str(DATA / "files" / name), *_flags(flags)],
                     codes=(ExitCode.OK, ExitCode.NOT_ACHIEVED))
    _check_identify(data)


def test_identify_json_on_a_simulated_record(tmp_path, capsys):
    """The issue's case: a simulate --record of central-leader at 5 kHz with 20 % noise
    (seed 6), its e 'determined' a numpy bool: was a TypeError and a traceback."""
    rec = tmp_path / "r.csv"
    assert main(["simulate", "central-leader", "--record", str(rec), "--rate", "5000",
                 "--noise", "0.2", "--seed", "6"]) == 0
    capsys.readouterr()
    data = _cli_json(capsys, ["identify", str(rec), *TEST])
    _check_identify(data)
    assert data["fit"]["restitution"]["determined"] in (True, False)


@pytest.mark.parametrize("argv", [
    ["simulate", "central-leader"],
    ["simulate", "central-leader", "--restitution", "1"],  # e = 1 wrote a NaN
    ["simulate", "open-center", "--restitution", "0", "--t-end", "0.05"],
    ["simulate", "central-leader", "--backend", "soft", "--t-end", "0.05"],
    ["simulate", "central-leader", "--backend", "mujoco", "--t-end", "0.05"],
    ["simulate", "central-leader", "--backend", "bullet", "--t-end", "0.05"],
    ["modes", "central-leader"],
    ["modes", "central-leader", "--backend", "beam"],
    ["contact", "--mass", "1", "--other-mass", "1", "--restitution", "0.75",
     "--touch-duration", "5e-3", "--dt", "1e-3"],
    ["paper"],
])
def test_every_json_command_writes_strict_json(argv, capsys):
    data = _cli_json(capsys, argv)
    assert isinstance(data, dict) and data


def test_the_sweep_journal_takes_numpy_scalars(tmp_path):
    """The CSV writer of the sweeps (compare.studies.sweep.journal.Journal): numpy's scalars as
    their Python values (a float32 NaN empty as a float's, not "nan"), read back as
    written."""
    import csv

    from treeimpact.compare.studies.sweep.journal import Journal

    journal = Journal(tmp_path / "j.csv", ["b", "i", "f", "nan", "g"])
    journal.append([{"b": np.bool_(True), "i": np.int64(3), "f": np.float64(0.1),
                     "nan": np.float32("nan"), "g": np.float32(0.5)}])
    journal.close()
    with open(tmp_path / "j.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows == [["b", "i", "f", "nan", "g"], ["True", "3", "0.1", "", "0.5"]]
