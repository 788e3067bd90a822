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
