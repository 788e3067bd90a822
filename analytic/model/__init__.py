"""Parameters, scenario files, the beam-to-SDOF reduction (eqs 1-11) and the two-body
model (Fig 3)."""
