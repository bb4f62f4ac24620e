"""``ideas-hpc report STORE --html`` in headless Chromium (issue 22): the page loads
without console errors and its screenshot shows the body mesh. Skipped, with the
reason, where Chromium is missing or cannot run."""

from __future__ import annotations

import re
import shutil
import subprocess
import tempfile

import numpy as np
import pytest
import xarray as xr

from ideas_hpc.cli import main
from small_stores import small_store

#: Collects uncaught errors and console.error calls into the DOM, where --dump-dom sees them.
PROBE = ("<script>window.__errors=[];window.addEventListener('error',e=>{window.__errors.push("
         "String(e.message))});const _ce=console.error;console.error=function(...a){"
         "window.__errors.push(a.join(' '));_ce.apply(console,a)};"
         "window.addEventListener('load',()=>setTimeout(()=>{const p=document.createElement("
         "'pre');p.id='probe-errors';p.textContent='ERRORS['+window.__errors.join('|')+']';"
         "p.dataset.plots=document.querySelectorAll('.js-plotly-plot').length;"
         "document.body.appendChild(p)},3000));</script>")


def _chromium() -> str:
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        pytest.skip("chromium not installed (apt-get install chromium; .ci/run does it as root)")
    return exe


def _run(exe: str, *args: str) -> subprocess.CompletedProcess:
    user = tempfile.mkdtemp(prefix="chromium-")
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             "--enable-unsafe-swiftshader", f"--user-data-dir={user}", "--enable-logging=stderr",
             "--v=0", "--window-size=1200,900", "--virtual-time-budget=20000"]
    try:
        r = subprocess.run([exe, *flags, *args], capture_output=True, text=True, timeout=180)
    except (OSError, subprocess.TimeoutExpired) as exc:
        pytest.skip(f"chromium cannot run here: {exc}")
    finally:
        shutil.rmtree(user, ignore_errors=True)
    return r


@pytest.fixture(scope="module", params=["monte-carlo", "design-exact"])
def page(request, tmp_path_factory):
    root = tmp_path_factory.mktemp("html")
    store = small_store(request.param, root)
    assert main(["report", str(store), "--out", str(root / "rep"), "--html"]) == 0
    return root / "rep" / "report.html", xr.open_zarr(store)


def test_page_is_self_contained(page):
    path, ds = page
    text = path.read_text()
    assert not re.search(r"<script[^>]*\bsrc=", text)       # plotly.js inlined: opens offline
    assert text.count("Plotly.newPlot") >= 3 and ds.attrs["shape_model"] in text
    assert "<h2>Summary</h2>" in text
    if "sample" in ds.dims and ds.sizes["sample"] > 1:
        assert "P(seen) over Monte Carlo samples" in text
    else:                                   # a design: trade curve and verification
        assert "coverage versus swarm size" in text and "threshold" in text


def test_page_loads_without_console_errors(page, tmp_path):
    exe = _chromium()
    path, _ = page
    probed = tmp_path / "probed.html"
    probed.write_text(path.read_text().replace("<head>", "<head>" + PROBE, 1))
    r = _run(exe, "--dump-dom", probed.as_uri())
    if r.returncode != 0 and not r.stdout:
        pytest.skip(f"chromium cannot run here: {r.stderr.strip().splitlines()[-1:]}")
    m = re.search(r'<pre id="probe-errors" data-plots="(\d+)">ERRORS\[(.*?)\]</pre>', r.stdout,
                  re.S)
    assert m, "the page never finished loading"
    assert m.group(2) == "", f"JavaScript errors: {m.group(2)}"
    assert int(m.group(1)) >= 3                                   # body, ring, distribution
    console = [ln for ln in r.stderr.splitlines() if "CONSOLE" in ln]
    assert not [ln for ln in console if re.search(r"Uncaught|\w+Error\b", ln)], console


def test_screenshot_shows_the_body_mesh(page, tmp_path):
    import matplotlib.image as mpimg

    exe = _chromium()
    path, _ = page
    shot = tmp_path / "shot.png"
    r = _run(exe, f"--screenshot={shot}", path.as_uri())
    if not shot.exists():
        pytest.skip(f"chromium wrote no screenshot: {r.stderr.strip().splitlines()[-1:]}")
    img = mpimg.imread(shot)[..., :3]
    assert img.shape[:2] == (900, 1200)
    scene = img[200:650, 150:850]             # the 3-D view is the first figure of the page
    colourful = (scene.max(axis=2) - scene.min(axis=2)) > 0.25    # the blue mesh, not the grid
    assert colourful.mean() > 0.05, f"3-D view blank: {colourful.mean():.3f} coloured"
    assert np.isfinite(img).all()
