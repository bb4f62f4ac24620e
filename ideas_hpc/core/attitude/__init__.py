"""Attitude kernels: rigid body with reaction wheels, MRPs, sliding-mode control, maneuvers, batches."""
