"""The README's images: every one it links exists, is a PNG and is small; none is orphaned."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MAX_BYTES = 300 * 1024
LINK = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def _links(doc: Path) -> list[str]:
    return LINK.findall(doc.read_text())


def test_link_pattern_finds_images_only():
    text = "see ![a b](x/y.png) and [not an image](z.png) ![c](w.png)"
    assert LINK.findall(text) == ["x/y.png", "w.png"]


def test_every_linked_image_exists_and_is_small():
    links = [(doc, link) for doc in (ROOT / "README.md", ROOT / "CONTRIBUTING.md")
             for link in _links(doc)]
    assert links, "the README embeds its figures"
    for doc, link in links:
        path = (doc.parent / link).resolve()
        assert path.is_file(), f"{doc.name} links {link}, which does not exist"
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n", f"{link} is not a PNG"
        assert path.stat().st_size < MAX_BYTES, f"{link}: {path.stat().st_size} bytes"


def test_every_committed_figure_is_linked():
    linked = {(ROOT / link).resolve() for link in _links(ROOT / "README.md")}
    for png in (ROOT / "docs" / "figures").glob("*.png"):
        assert png.resolve() in linked, f"{png.name} is in docs/figures but not in the README"
