"""The reference area of a setup's world (issue 42): the requirement's vertex weights
with this setup's body and its Sun at closest approach.

:func:`reference_areas` is what the designers' banks weigh their rows by: the vertex
areas for ``reference = "surface"`` (exactly the array every bank read before), the area
lit at TCA for ``"lit_at_tca"`` (:func:`ideas_hpc.mapping.reference.reference_weights`).
A drawn world calls it with the setup flown in that world (``world.flown(setup)``): its
own shape, pole, phase and Sun.
"""

from __future__ import annotations

import numpy as np

from ideas_hpc.mapping.reference import reference_weights

__all__ = ["reference_areas", "sun_at_closest_approach"]


def sun_at_closest_approach(setup) -> np.ndarray:
    """(3,) unit body -> Sun direction in T at the geometry's closest approach."""
    t_ca = setup.geometry.closest_approach_s(setup)
    return np.asarray(setup.sun_T([t_ca])[0], dtype=np.float64)


def reference_areas(setup, requirement) -> np.ndarray:
    """(V,) float64, m^2: the vertex weights of ``requirement.reference`` in ``setup``'s
    world (module docstring; not normalised)."""
    if requirement.reference == "surface":     # no Sun read: bit-identical to the areas
        return np.asarray(setup.body.shape.vertex_areas, dtype=np.float64)
    return reference_weights(setup.body.shape, sun_at_closest_approach(setup), requirement)
