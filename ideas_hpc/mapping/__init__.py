"""Mapping models: coverage options and the boundary of the coverage and quality kernels (``core.mapping``)."""
