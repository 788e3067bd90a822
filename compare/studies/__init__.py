"""Studies built on sweeps (floor 3 of compare, docs/architecture.md): each runs as one or
more sweeps (:mod:`treeimpact.compare.studies.sweep`) and reduces their tables to an answer.

* :mod:`.contact_scan` - the shortest contact duration for which the 1-DOF model holds;
* :mod:`.small_e` - up to which e each consequence of "e is small" holds;
* :mod:`.sensitivity` - the answer's error bars over the unmeasured inputs (Morris, SALib);
* :mod:`.ident_study` - the identification validated on synthetic pendulum-test records
  (:mod:`.ident_records` the records and their identification, :mod:`.ident_maps` its maps);
* :mod:`.ident_fits` - the report's record fits (the exact 1-DOF model fitted to each rung);
* :mod:`.speed` - speed-accuracy curves per engine.
"""
