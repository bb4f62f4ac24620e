"""The images of the README and the docs: every one linked exists, is a PNG and is small;
every committed figure in docs/figures is shown somewhere; no page links outside the
repository."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAX_BYTES = 300 * 1024
LINK = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")
ANY_LINK = re.compile(r"\]\(([^)\s]+)\)")


def _pages() -> list[Path]:
    """The README, CONTRIBUTING and every Markdown page of the docs site."""
    return [ROOT / "README.md", ROOT / "CONTRIBUTING.md",
            *sorted((ROOT / "docs").rglob("*.md"))]


def _links(doc: Path) -> list[str]:
    return LINK.findall(doc.read_text(encoding="utf-8"))


def test_link_pattern_finds_images_only():
    text = "see ![a b](x/y.png) and [not an image](z.png) ![c](w.png)"
    assert LINK.findall(text) == ["x/y.png", "w.png"]


def test_every_linked_image_exists_and_is_small():
    links = [(doc, link) for doc in _pages() for link in _links(doc)
             if not link.startswith(("http://", "https://"))]
    assert links, "the docs embed their figures"
    for doc, link in links:
        path = (doc.parent / link).resolve()
        assert path.is_file(), f"{doc.relative_to(ROOT)} links {link}, which does not exist"
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"{link} is not a PNG"
        assert path.stat().st_size < MAX_BYTES, f"{link}: {path.stat().st_size} bytes"


def test_every_committed_figure_is_linked():
    linked = {(doc.parent / link).resolve() for doc in _pages() for link in _links(doc)}
    pngs = list((ROOT / "docs" / "figures").glob("*.png"))
    assert pngs, "docs/figures holds the gallery's figures"
    for png in pngs:
        assert png.resolve() in linked, f"{png.name} is in docs/figures but on no page"


def test_no_page_points_outside_the_repository():
    """A clone must be enough: no relative link or path of the README or the docs climbs out
    of the checkout (CONTRIBUTING.md, for developers, names the shared tools)."""
    for doc in _pages():
        if doc.name == "CONTRIBUTING.md":
            continue
        text = doc.read_text(encoding="utf-8")
        assert "../shared" not in text, f"{doc.relative_to(ROOT)} points to ../shared"
        for link in ANY_LINK.findall(text):
            if link.startswith(("http://", "https://", "#", "mailto:")):
                continue
            target = (doc.parent / link.split("#")[0]).resolve()
            assert target.is_relative_to(ROOT), f"{doc.relative_to(ROOT)} links {link}"
