"""The paper's genetic algorithm (eqs. 15-18) and its mask bank."""
