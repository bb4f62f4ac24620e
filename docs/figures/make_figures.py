"""Regenerate the README's encounter figures (docs/figures/*.png), small enough to commit.

From the project root, with IDEAS_HPC_DATA pointing at the real Eros data
(eros001708):

    ideas-hpc run campaigns/eros-fast-encounter.toml --out /tmp/enc.zarr
    ideas-hpc report /tmp/enc.zarr --out /tmp/enc-report
    ideas-hpc scan-encounter campaigns/eros-fast-encounter.toml \\
        --set coverage.require_lit=false --plot /tmp/enc-scan.png
    python docs/figures/make_figures.py /tmp/enc-report /tmp/enc-scan.png

and, for the smoke run's figures (the main job's kind at the smoke run's size),
a third argument:

    ideas-hpc run campaigns/eros-design-quick.toml --out /tmp/quick.zarr
    ideas-hpc report /tmp/quick.zarr --out /tmp/quick-report
    python docs/figures/make_figures.py /tmp/enc-report /tmp/enc-scan.png /tmp/quick-report

The report draws at 120 dpi; this copies the figures the README shows at
3/4 of that size (90 dpi), as 256-colour PNGs (each well under 150 KB).
"""

from __future__ import annotations

import sys
from pathlib import Path

from PIL import Image

HERE = Path(__file__).resolve().parent
#: report figure -> README name
REPORT = {"fig22_trajectories.png": "encounter_trajectories.png",
          "design_coverage_vs_n.png": "encounter_coverage_vs_n.png",
          "quality_mapped.png": "encounter_mapped.png"}
#: smoke-run report figure -> gallery name
SMOKE = {"design_reliability_curve.png": "smoke_reliability_curve.png",
         "design_validation_coverage.png": "smoke_validation_coverage.png",
         "design_ring.png": "smoke_ring.png",
         "fig26_sigma_error.png": "smoke_sigma_error.png"}
SCALE = 0.75


def shrink(src: Path, dst: Path) -> int:
    """Copy ``src`` to ``dst`` at ``SCALE`` of its size, 256 colours; returns the bytes."""
    im = Image.open(src).convert("RGB")
    im = im.resize((round(im.width * SCALE), round(im.height * SCALE)), Image.LANCZOS)
    im.quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(dst, optimize=True)
    return dst.stat().st_size


def main(report_dir: str | None, scan_png: str | None, smoke_dir: str | None = None) -> None:
    pairs = [(Path(report_dir) / a, HERE / b) for a, b in REPORT.items()] if report_dir else []
    if scan_png:
        pairs.append((Path(scan_png), HERE / "encounter_scan.png"))
    if smoke_dir is not None:
        pairs += [(Path(smoke_dir) / a, HERE / b) for a, b in SMOKE.items()]
    for src, dst in pairs:
        print(f"{dst.name}: {shrink(src, dst) / 1024:.0f} KB")


if __name__ == "__main__":
    main(*[a or None for a in sys.argv[1:4]])   # "" skips the encounter figures
