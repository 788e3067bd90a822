"""The model-validity study (``treeimpact sweep --preset``, ``treeimpact report
--with-study``; floor 6 of compare, docs/architecture.md): presets, the study's sweeps and
studies run on one pool, its page (with the report's templates) and its run beside the report.

* :mod:`.study` - presets ``default`` and ``full``; study.html, study.md, results table;
* :mod:`.sensitivity_study` - its sensitivity part;
* :mod:`.study_job` - a study run in a child process beside the report.

The command that runs a study, ``treeimpact sweep``, is
:mod:`treeimpact.compare.commands.sweep` (floor 7).
"""
