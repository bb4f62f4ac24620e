"""Dynamics kernels: propagation (DOP853), force model record, gravity, targeting, ephemeris, frames."""
