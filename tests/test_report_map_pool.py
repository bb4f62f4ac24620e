"""The report's body maps drawn in a second process (:mod:`ideas_hpc.report.map_pool`).

The oracle is the same map drawn in this process: the child's PNG must be the same
file, byte for byte; a map that fails in the child must fail at :meth:`MapPool.finish`
with the map's own error. (``ideas-hpc report`` asks for the child: the CLI's report
tests run it.)
"""

from __future__ import annotations

import numpy as np
import pytest

from ideas_hpc.base.errors import InputError
from ideas_hpc.report.map_pool import MapPool


def test_maps_from_the_child_are_the_in_process_maps(tmp_path):
    from ideas_hpc.body.analytic import eros_ellipsoid
    from ideas_hpc.plots import figures
    from ideas_hpc.plots.coverage_map import render_coverage_map

    shape = eros_ellipsoid(resolution=2)
    x = shape.vertices_T[:, 0] / 1e3
    cases = {"observed.png": dict(values=x > 0.0, kind="observed"),
             "first_seen.png": dict(values=np.where(x > -2.0, x + 20.0, np.nan),
                                    kind="first_seen"),
             "value.png": dict(values=np.abs(x), kind="value", label="km")}
    with MapPool(parallel=True) as pool:
        assert pool.parallel
        for name, kw in cases.items():
            assert pool.render(shape, path=tmp_path / "there" / name, **kw) == \
                tmp_path / "there" / name
    for name, kw in cases.items():
        render_coverage_map(shape, path=tmp_path / "here" / name, **kw)
    figures.plt.close("all")
    for name in cases:
        assert (tmp_path / "here" / name).read_bytes() == \
            (tmp_path / "there" / name).read_bytes(), name


def test_a_map_that_fails_in_the_child_fails_the_report(tmp_path):
    from ideas_hpc.body.analytic import sphere_mesh

    shape = sphere_mesh(1000.0, resolution=1)
    pool = MapPool(parallel=True)
    assert pool.parallel
    path = pool.render(shape, np.zeros(3), tmp_path / "bad.png")   # 3 values, not one per vertex
    assert path == tmp_path / "bad.png"
    with pytest.raises(InputError, match="one per vertex"):
        pool.finish()
    assert not pool.parallel
