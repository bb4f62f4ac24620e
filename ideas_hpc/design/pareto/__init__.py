"""Multi-objective design (NSGA-II) over the objective registry."""
