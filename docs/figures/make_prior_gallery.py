"""Redraw docs/figures/prior_gallery.png: eight worlds of the built-in Eros-class prior.

From the project root (no data path needed)::

    python docs/figures/make_prior_gallery.py

Draws worlds k = 0..7 of seed 0 (``eros_class_prior().draw(0, k)``), renders them with
:func:`ideas_hpc.plots.prior.prior_gallery` and stores a 256-colour PNG (< 150 KB).
"""

from __future__ import annotations

from pathlib import Path

from PIL import Image

from ideas_hpc.body.target_prior import eros_class_prior
from ideas_hpc.plots.prior import prior_gallery

HERE = Path(__file__).resolve().parent


def main() -> None:
    prior = eros_class_prior()
    worlds = [prior.draw(0, k) for k in range(8)]
    out = HERE / "prior_gallery.png"
    prior_gallery(worlds, out, title="Eros-class prior: eight worlds (seed 0), one scale")
    Image.open(out).convert("RGB").quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(
        out, optimize=True)
    print(f"{out.name}: {out.stat().st_size / 1024:.0f} KB")


if __name__ == "__main__":
    main()
