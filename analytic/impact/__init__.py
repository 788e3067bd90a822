"""The exact impact solver of the paper (eqs 12-35): free flights in closed form, Newton
impacts, moving together, and ``simulate``."""
