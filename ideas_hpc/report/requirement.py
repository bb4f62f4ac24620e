"""What a store's coverage means, in one line for the summary and the HTML page (issue 42).

A store records its coverage reference and its requirement's label
(:func:`ideas_hpc.campaign.setup.requirement_attrs`: ``coverage_reference``,
``requirement_kind``, ``requirement``); a store written before them is the whole surface,
and geometric unless it holds a ``mapped`` variable (a ``[coverage]`` requirement).
"""

from __future__ import annotations

__all__ = ["coverage_meaning", "GEOMETRIC_WHOLE"]

#: The paper's map, worded as :attr:`ideas_hpc.mapping.requirement.Requirement.label` does.
GEOMETRIC_WHOLE = "geometric (thermal, the paper's) map of the whole surface"


def coverage_meaning(ds) -> str:
    """``"coverage requirement: <label>"`` of store ``ds`` (module docstring)."""
    label = ds.attrs.get("requirement")
    if not label:
        label = (GEOMETRIC_WHOLE if "mapped" not in ds else
                 "map of the whole surface meeting the [coverage] requirement")
    return f"coverage requirement: {label}"
