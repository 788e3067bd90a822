"""Issue 41 item 3: ``simulate``'s table pushed ``crown_peak_acceleration`` (23 characters, a
22-wide column) one place right of every other row. Each column is as wide as its widest
cell: every row's value ends where its header does."""

from __future__ import annotations

import pytest

from treeimpact.compare.interface.cli import main


@pytest.mark.parametrize("backend", ["analytic", "soft"])
def test_every_value_ends_under_its_header(capsys, backend):
    assert main(["simulate", "central-leader", "--backend", backend]) == 0
    lines = capsys.readouterr().out.splitlines()
    head = next(i for i, line in enumerate(lines) if line.lstrip().startswith("metric "))
    backend_name = lines[head].split()[1]
    end = lines[head].index(backend_name) + len(backend_name)
    rows = lines[head + 1:]
    assert any(r.split()[0] == "crown_peak_acceleration" for r in rows)
    for row in rows:
        key, value = row.split()[:2]
        assert row.index(value, len(key) + 2) + len(value) == end, (row, lines[head])
    model = lines[2:head - 1]
    ends = {line.index(line.split()[1], len(line.split()[0]) + 2) + len(line.split()[1])
            for line in model}
    assert ends == {end}, model
