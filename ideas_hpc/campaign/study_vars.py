"""The store variables and attrs every answer of ``ideas-hpc study`` shares
(:mod:`ideas_hpc.campaign.study`, :mod:`ideas_hpc.campaign.study_distance`)."""

from __future__ import annotations

import numpy as np

#: What no data chose, written with every answer.
CHOSE_NOTHING = ("the swarm is the store's (swarm_angle); the level, threshold, seed and "
                 "bank size are the campaign's; the sigmas, distances, M and K are the "
                 "command's")


def search_vars(dim: str, rows: list) -> dict:
    """The fewest-N search's variables of ``rows`` (:meth:`Study.fewest`) along ``dim``."""
    return {
        "fewest_n": (dim, np.array([r["n"] for r in rows], dtype=np.int64), {
            "units": "1", "long_name": "fewest N found with P_bank >= the level (-1: none up "
                                       "to n_max)"}),
        "fewest_bound": (dim, np.array([r["bound"] for r in rows], dtype=np.int64), {
            "units": "1", "long_name": "proven lower bound on that N (-1: none reached)"}),
        "fewest_status": (dim, labels(*[r["status"] for r in rows]), {
            "units": "1", "long_name": "status of the search (optimal: N proven fewest)"}),
        "fewest_probability": (dim, np.array([r["probability"] for r in rows]), {
            "units": "1", "long_name": "P_bank of the fewest-N swarm"}),
        "swarm_probability": (dim, np.array([r["swarm_probability"] for r in rows]), {
            "units": "1", "long_name": "P_bank of the designed swarm (common random "
                                       "numbers across the rows)"})}


def labels(*names) -> np.ndarray:
    """Labels as variable-length strings (zarr 3 has no specification of fixed-length ones)."""
    return np.array(names, dtype=object)


def answer_attrs(st, **more) -> dict:
    return {"campaign_seed": int(st.c.config.seed), "chose_nothing": CHOSE_NOTHING,
            "success_probability": st.p, "bank_level": st.level,
            "reliability_threshold": st.need, **more}
