"""Fly a design's swarm at targets the project did not generate, and pool them (issue 42).

A design under a target prior is validated on worlds drawn from that same prior; a
reviewer also wants truths the prior did not make. This script flies the stored swarm
(``ideas-hpc validate STORE --truth-...``, :func:`ideas_hpc.campaign.validate_store.
validate_store` with a :class:`~ideas_hpc.campaign.validate_truth.TruthOptions`) at:

* the NASA PDS shape model of 433 Eros (``eros001708``, read from ``IDEAS_HPC_DATA``;
  left out, and said so, without it) at its IAU pole, at four rotation phases and at two
  poles about 10 deg (one sigma of the built-in prior) off the nominal one;
* three triaxial ellipsoids of the class's size with other axis ratios, made here.

Each truth gets its own ``--samples`` fresh draws of the navigation errors, dispersions
and failures (consecutive blocks of the validation stream: nothing here chose the
swarm, and no two truths share a draw), and the pool is the
sample-weighted P-hat with its lower bound at the store's confidence
(:func:`~ideas_hpc.campaign.validate_store.pooled`).

    python analysis/independent_truths.py STORE [--samples 256]
"""

from __future__ import annotations

import argparse
import math

from ideas_hpc.body.datapath import have_data_file
from ideas_hpc.campaign.validate_store import pooled, validate_store
from ideas_hpc.campaign.validate_truth import TruthOptions

#: (shape, pole RA,Dec deg or None for the design's nominal, phase at TCA deg or None)
EROS = [("eros001708", None, ph) for ph in (0.0, 90.0, 180.0, 270.0)] + \
       [("eros001708", "20,10", 45.0), ("eros001708", "5,26", 135.0)]
ELLIPSOIDS = [("ellipsoid:15,6.5,5.2", "11,17", 40.0), ("ellipsoid:13,8,6", "20,25", 200.0),
              ("ellipsoid:17,5.5,5.5", "5,10", 310.0)]


def _options(shape, pole, phase) -> TruthOptions:
    radec = None if pole is None else tuple(math.radians(float(x)) for x in pole.split(","))
    return TruthOptions(shape=shape, pole_ra_dec_rad=radec,
                        phase_rad=None if phase is None else math.radians(phase))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("store")
    ap.add_argument("--samples", type=int, default=256)
    a = ap.parse_args(argv)
    truths = list(ELLIPSOIDS)
    if have_data_file("eros001708.tab"):
        truths = EROS + truths
    else:                      # no data path: the real shape is left out, and said so
        print("eros001708 left out: no eros001708.tab under IDEAS_HPC_DATA")
    vals = []
    for i, (shape, pole, phase) in enumerate(truths):
        # each truth its own block of the validation stream: the pool's samples are
        # independent draws (common draws would make the pooled bound optimistic)
        v = validate_store(a.store, samples=a.samples, first=i * a.samples, progress=False,
                           truth=_options(shape, pole, phase))
        vals.append(v)
        print(f"{shape:24s} pole {pole or 'nominal':8s} phase {phase:5.0f} deg: P-hat "
              f"{v.p_hat:.4f}, lower bound {v.lower:.4f}")
    print(pooled(vals).line())


if __name__ == "__main__":
    main()
