"""tests/same_outputs.py: what it calls the same (wall times, row order) and what not (a float's
last bit, a figure's bytes, a file only one folder has)."""

import json

import pandas as pd

from tests import same_outputs


def _folder(root, x_max, wall, rows, png=b"\x89PNG1"):
    root.mkdir()
    (root / "report.json").write_text(json.dumps(
        {"runs": [{"x_max": x_max, "wall_s": wall}], "provenance": {"git_commit": str(wall)}}))
    pd.DataFrame(rows, columns=["point", "x_max", "worker"]).to_csv(root / "results.csv",
                                                                      index=False)
    (root / "fig.png").write_bytes(png)
    return root


def test_wall_times_and_finishing_order_are_not_differences(tmp_path):
    a = _folder(tmp_path / "a", 0.1, 1.0, [("p1", 1.0, 0), ("p2", 2.0, 1)])
    b = _folder(tmp_path / "b", 0.1, 2.5, [("p2", 2.0, 0), ("p1", 1.0, 1)])
    assert same_outputs.compare(a, b) == []
    assert same_outputs.main([str(a), str(b)]) == 0


def test_one_ulp_a_figure_byte_and_a_missing_file_are_differences(tmp_path):
    a = _folder(tmp_path / "a", 0.1, 1.0, [("p1", 1.0, 0)])
    b = _folder(tmp_path / "b", 0.1 + 2 ** -56, 1.0, [("p1", 1.0 + 2 ** -52, 0)], b"\x89PNG2")
    (b / "extra.json").write_text("{}")
    found = same_outputs.compare(a, b)
    assert any(line.startswith("report.json: /runs[0]/x_max") for line in found)
    assert any(line.startswith("results.csv: row 0 x_max") for line in found)
    assert "fig.png: bytes differ" in found and "extra.json: only after" in found
    assert same_outputs.main([str(a), str(b)]) == 1
    assert same_outputs.main([str(a)]) == 2


def test_a_missing_string_cell_is_compared(tmp_path):
    """A Parquet string column with pandas' NA (a sweep's ``error`` of a run that passed):
    missing in both is the same, missing in one is a difference, not a TypeError."""
    def table(name, errors):
        path = tmp_path / name
        path.mkdir()
        pd.DataFrame({"point": ["p1", "p2"], "error": pd.array(errors, dtype="string")}
                     ).to_parquet(path / "results.parquet", index=False)
        return path

    a = table("a", [None, "diverged"])
    assert same_outputs.compare(a, table("b", [None, "diverged"])) == []
    found = same_outputs.compare(a, table("c", ["failed", "diverged"]))
    assert [line.split(":")[0] for line in found] == ["results.parquet"]
