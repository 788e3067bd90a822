"""treeimpact.analytic: the physics, no engine and no command line (SI units throughout).

Subpackages, each with one job, from the bottom floor up (no module imports a higher one;
tests/test_layers.py keeps it so):

* :mod:`.errors`, :mod:`.results`: the errors and the result types every backend returns;
* :mod:`.model`: parameters, scenario files, the beam-to-SDOF reduction (eqs 1-11), the
  two-body model of Fig 3, a tree's scenario from measured M_T, K_T, C_T;
* :mod:`.records`: metrics from a sampled contact record (the rule every backend shares);
* :mod:`.impact`: the exact Newton-restitution solver (eqs 12-35) and ``simulate``;
* :mod:`.contact`: the pad law (k_c, c_c <-> e, duration), the soft-contact rung, the
  matched-loss model, the engines' time-step rule;
* :mod:`.continuum`: the Euler-Bernoulli beam, the hinged chain, modes, the beam impact;
* :mod:`.identify`: the paper's procedure (eqs 39-48) and the whole-record fit;
* :mod:`.engine`: what every physics engine shares (interface, checks, generated files);
* :mod:`.paper`: Table 1 reproduced, the errata, the contact fitted to the measurements.

The public API is :mod:`treeimpact` (docs/api.md).
"""
