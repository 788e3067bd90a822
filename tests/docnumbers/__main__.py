"""``python -m tests.docnumbers {numbers REPORT_DIR,write,check}`` from the checkout: write
docs/numbers.json from a report, rewrite the pages' generated blocks, or list every quoted
number and block that drifted (exit 1 when one did)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import __doc__ as PACKAGE_DOC
from .base import NUMBERS, ROOT
from .marks import check_blocks, check_marks, write_blocks
from .numbers_file import write_numbers


def main(argv=None) -> int:
    """Run one command (``argv``: its arguments, default ``sys.argv[1:]``); returns the exit
    code: 0, or 1 when the report and this checkout disagree (``numbers``) or a page
    drifted (``check``)."""
    p = argparse.ArgumentParser(prog="python -m tests.docnumbers",
                                description=PACKAGE_DOC.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    sn = sub.add_parser("numbers", help="write docs/numbers.json from a report directory "
                                        "(make report) and the cheap part rerun now")
    sn.add_argument("report_dir", help="the directory of report.json (make report's OUT)")
    sub.add_parser("write", help="rewrite the generated blocks of the pages")
    sub.add_parser("check", help="list every quoted number and block that drifted")
    args = p.parse_args(argv)
    if args.command == "numbers":
        drift = write_numbers(Path(args.report_dir))
        print(f"wrote {NUMBERS.relative_to(ROOT)}")
        for k in drift:
            print(f"  the report and this checkout disagree on {k}", file=sys.stderr)
        return 1 if drift else 0
    if args.command == "write":
        for name in write_blocks():
            print(f"rewrote {name}")
        return 0
    problems = check_marks() + check_blocks()
    for line in problems:
        print(line)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
