"""Translational dynamics models: force model settings and trajectories (boundary of ``core.dynamics``)."""
