"""Issue 41 item 8: docs/contact-settings.md said "2.5 steps per touch" where ``treeimpact
contact`` prints "3 steps" for the same case. The page's count of steps with a normal force
is the one the command prints (its step length, touch / dt, is a marked number of
docs/numbers.json)."""

from __future__ import annotations

import re
from pathlib import Path

from tests.docnumbers.rerun import DEFAULT_STEP_CASE
from treeimpact.compare.interface.cli import main

DOC = Path(__file__).resolve().parents[1] / "docs" / "contact-settings.md"


def test_the_page_counts_the_steps_the_command_prints(capsys):
    m1, m2, e, touch, dt = DEFAULT_STEP_CASE
    assert main(["contact", "--mass", f"{m1:g}", "--other-mass", f"{m2:g}", "--restitution",
                 f"{e:g}", "--touch-duration", f"{touch:g}", "--dt", f"{dt:g}",
                 "--engine", "mujoco"]) == 0
    out = capsys.readouterr().out
    printed = re.search(r"MuJoCo solref \(direct\) .*?, (\d+) steps\)", out)
    assert printed, out
    text = " ".join(DOC.read_text().split())
    said = re.findall(r"in which the command counts (\d+) steps with a normal force", text)
    assert said == [printed.group(1)], (said, printed.group(0))
