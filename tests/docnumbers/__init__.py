"""One source for every number the README and docs/ quote (issue 26), and the pages checked
against it.

Where the numbers come from:

* ``docs/numbers.json``: the results of the code, derived from a report (``make report``) by
  ``python -m tests.docnumbers numbers REPORT_DIR`` (from the checkout), which also reruns the cheap
  part (:func:`.rerun.cheap_numbers`: the shipped trees' analytic rungs and mechanism, the beam
  studies, ``treeimpact contact``'s collisions, the models at the contact fitted to the
  paper's trees, the code's constants; seconds) and says where the report disagrees with it;
  it keeps only the keys the pages quote (and what the tests read), so a new mark needs
  ``numbers`` rerun;
* ``docs/results/contact-fit.json``: the output of ``treeimpact paper --fit-contact --json``;
* ``docs/results/identify-validation.json``: the identification's validation set and accuracy
  (``tests/data/identify/make_records.py --evaluate --numbers FILE`` and ``--accuracy N``),
  its numbers under ``identify.``;
* ``benchmarks/results/*.json``: each benchmark's own results file (``make benchmark``,
  ``benchmarks/_results.py``), with the machine and its load; timings are quoted from there
  only.

How a page quotes one (the markdown conventions, invisible when rendered):

* ``+8.6 %<!-- check: gap_pct.x_max.open-center -->``: the number (or list of numbers: a
  range ``57-213``, ``-12..-14``, ``9, 21 and 33``, ``+8.5 / +17.8``) just before the
  comment, a unit word allowed between, is the value of the key (a number, or a list of as
  many; one number may stand for a [min, max] range whose ends both round to it) rounded to
  the digits the page prints: it may differ by at most half a unit of its last digit (the
  page quotes a rounded value; a finer difference is the rounding itself). ``check-max``:
  the page's number is an upper bound of the value ("within 0.4 %"), ``check-min`` a lower
  bound; `` ~10%`` after the key allows that relative difference instead (an "about").
* ``<!-- BEGIN generated: NAME -->`` ... ``<!-- END generated: NAME -->``: a block written by
  ``python -m tests.docnumbers write`` from the sources (:data:`.tables.GENERATED`); the
  check regenerates it in memory and compares it number by number (as floats, at the
  digits printed) and word by word.

``python -m tests.docnumbers check`` lists every quoted number and block that
drifted; ``tests/test_doc_numbers.py`` fails on one. SI units in the sources; keys say their
unit where it is not SI (``_pct``, ``_ms``, ``_kg``) and :data:`.base.DISPLAY` gives the rungs'
values' (``value.*``).

Where the code is (tooling of the checkout, not installed with treeimpact):

* :mod:`.base` - the sources' paths, the trees, display units, rounding;
* :mod:`.from_report` - the numbers of a report (or of ladders run now);
* :mod:`.from_files` - the numbers of the checked-in results files; all of them
  (:func:`~.from_files.numbers`);
* :mod:`.rerun` - the cheap part, rerun now;
* :mod:`.tables` - the generated blocks;
* :mod:`.marks` - the pages checked against the numbers;
* :mod:`.numbers_file` - docs/numbers.json written from a report;
* :mod:`.__main__` - the command (``numbers``, ``write``, ``check``).
"""

from .base import CONTACT_FIT, NUMBERS, ROOT, TREES
from .from_files import numbers
from .marks import PAGES, check_blocks, check_marks, check_now, quoted, used_keys, write_blocks
from .numbers_file import FIGURES, write_numbers
from .rerun import cheap_numbers

__all__ = ["CONTACT_FIT", "FIGURES", "NUMBERS", "PAGES", "ROOT", "TREES", "cheap_numbers",
           "check_blocks", "check_marks", "check_now", "numbers", "quoted", "used_keys",
           "write_blocks", "write_numbers"]
