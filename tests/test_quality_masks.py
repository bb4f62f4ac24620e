"""Per-spacecraft quality rows (ideas_hpc.core.mapping.quality_masks) against the NumPy
brute force of tests/test_quality_eros.py, flown one spacecraft at a time."""

from __future__ import annotations

import numpy as np
import pytest

from ideas_hpc.mapping.coverage import quality_per_spacecraft
from ideas_hpc.mapping.options import CoverageOptions
from test_quality_eros import CASES, DEG, eros_views, quality_oracle


@pytest.mark.parametrize("case", sorted(CASES))
def test_rows_match_brute_force_per_spacecraft(eros1708, case):
    shape = eros1708.shape
    r, C, t, sun = eros_views()
    opts = CoverageOptions(**CASES[case])
    eta = 20 * DEG
    rows = quality_per_spacecraft(shape, r, C, t, eta, 1e-3, 1e6, options=opts, sun_T=sun)
    stereo_any = 0
    for k in range(r.shape[0]):
        one = np.zeros(r.shape[0], bool)
        one[k] = True
        ref = quality_oracle(shape, r, C, t, eta, 1e-3, 1e6, opts, sun, one)
        np.testing.assert_array_equal(rows["stereo"][k], ref["stereo"], err_msg=f"stereo {k}")
        np.testing.assert_array_equal(rows["mapped"][k], ref["mapped"], err_msg=f"mapped {k}")
        np.testing.assert_allclose(rows["resolution"][k],
                                   np.where(np.isnan(ref["best_resolution"]), np.inf,
                                            ref["best_resolution"]), rtol=1e-12)
        stereo_any += rows["stereo"][k].sum()
        # usable: the requirement without stereo
        if opts.require_stereo:
            nost = CoverageOptions(**{**CASES[case], "require_stereo": False})
            ref_u = quality_oracle(shape, r, C, t, eta, 1e-3, 1e6, nost, sun, one)
            np.testing.assert_array_equal(rows["usable"][k], ref_u["mapped"])
    assert stereo_any > 0 and rows["usable"].any(axis=1).sum() >= 2


@pytest.mark.parametrize("case", ["exact-occl-all-limits", "illum-elev-stereo-detector"])
def test_swarm_stereo_is_own_tracks_plus_pairs_on_every_subset(eros1708, case):
    """The designers' stereo model: a subset maps a vertex iff one member's own track
    or one pair of members does. Checked against the quality pass of every subset."""
    import itertools

    from ideas_hpc.core.mapping.stereo_pairs import pair_index
    from ideas_hpc.mapping.coverage import compute_coverage, stereo_pair_table

    shape = eros1708.shape
    r, C, t, sun = eros_views()
    opts = CoverageOptions(**CASES[case])
    eta = 20 * DEG
    rows = quality_per_spacecraft(shape, r, C, t, eta, 1e-3, 1e6, options=opts, sun_T=sun)
    pairs = stereo_pair_table(shape, r, C, t, eta, 1e-3, 1e6, options=opts, sun_T=sun)
    n = r.shape[0]
    assert pairs.shape == (n * (n - 1) // 2, shape.n_vertices) and pairs.any()
    from_pairs_only = 0
    for size in range(1, n + 1):
        for sub in itertools.combinations(range(n), size):
            active = np.zeros(n, bool)
            active[list(sub)] = True
            q = compute_coverage(shape, r, C, t, eta, 1e-3, 1e6, options=opts, sun_T=sun,
                                 active=active).quality
            own = rows["mapped"][list(sub)].any(axis=0)
            model = own.copy()
            for a, b in itertools.combinations(sub, 2):
                model |= pairs[pair_index(a, b, n)]
            np.testing.assert_array_equal(model, q.mapped, err_msg=str(sub))
            from_pairs_only += int((model & ~own).sum())
    assert from_pairs_only > 0      # the test sees stereo that needs two spacecraft
