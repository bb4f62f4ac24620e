"""Per-spacecraft quality rows (ideas_hpc.core.quality_masks) against the NumPy
brute force of tests/test_quality_eros.py, flown one spacecraft at a time."""

from __future__ import annotations

import numpy as np
import pytest

from ideas_hpc.mapping import CoverageOptions, quality_per_spacecraft
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
