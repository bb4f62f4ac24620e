"""Redraw docs/figures/study_bplane.png and study_answers.png (docs/study.md).

From the project root, after the design and its study (a few minutes, no data path)::

    ideas-hpc run campaigns/eros-class-flyby.toml --out eros-class.zarr
    ideas-hpc study eros-class.zarr
    python docs/figures/make_study_figures.py eros-class.zarr

Writes the store's report (``ideas-hpc report``) and keeps its two study figures as
256-colour PNGs (< 150 KB).
"""

from __future__ import annotations

import sys
from pathlib import Path

from PIL import Image

from ideas_hpc.report.write import write_report

HERE = Path(__file__).resolve().parent


def main(store: str) -> None:
    report = write_report(store).parent
    for name in ("study_bplane.png", "study_answers.png"):
        out = HERE / name
        Image.open(report / name).convert("RGB").quantize(
            colors=256, method=Image.Quantize.MEDIANCUT).save(out, optimize=True)
        print(f"{out.name}: {out.stat().st_size / 1024:.0f} KB")


if __name__ == "__main__":
    main(sys.argv[1])
