"""The model-validity study (``treeimpact sweep --preset``, ``treeimpact report
--with-study``; inside report/, floor 4 of compare, docs/architecture.md): presets, the
study's sweeps and studies run on one pool, its page (with the report's templates) and its
run beside the report.

* :mod:`.presets` - the registry of presets (``--preset NAME``): ``default`` and ``full``;
* :mod:`.study` - the validity study: study.html, study.md, results table;
* :mod:`.design_study` - the design map, preset ``design`` (registered below);
* :mod:`.sensitivity_study` - its sensitivity part;
* :mod:`.study_job` - a study run in a child process beside the report.

The command that runs a study, ``treeimpact sweep``, is
:mod:`treeimpact.compare.interface.commands.sweep` (floor 5).
"""

from . import design_study  # noqa: F401,E402 - registers the design preset
