"""Reading an accugrid HTML report back (html.parser): the verdict, the text, every tag's
attributes; and the checks every report must pass (self-contained, inputs with SHA-256)."""

from __future__ import annotations

import base64
import hashlib
from html.parser import HTMLParser
from pathlib import Path

__all__ = ["Page", "check_report"]

PNG = b"\x89PNG\r\n\x1a\n"


class Page(HTMLParser):
    """Every tag's attributes, the text, and the verdict box's text."""

    def __init__(self):
        super().__init__()
        self.attrs: list[tuple[str, dict]] = []
        self.text: list[str] = []
        self.verdict: list[str] = []
        self._in_verdict = False

    def handle_starttag(self, tag, attrs):
        self.attrs.append((tag, dict(attrs)))
        self._in_verdict = "verdict" in (dict(attrs).get("class") or "")

    def handle_endtag(self, tag):
        self._in_verdict = False

    def handle_data(self, data):
        self.text.append(data)
        if self._in_verdict:
            self.verdict.append(data.strip())


def check_report(path: Path, inputs: list[Path], figures: int) -> Page:
    """Parse the report at ``path`` and assert: the SHA-256 of each of ``inputs`` is in its
    text, ``figures`` images, each an inline PNG that decodes, no URL but data: ones."""
    page = Page()
    html = path.read_text()
    page.feed(html)
    text = " ".join(page.text)
    for item in inputs:
        assert hashlib.sha256(item.read_bytes()).hexdigest() in text, item
    images = [a for tag, a in page.attrs if tag == "img"]
    assert len(images) == figures
    for image in images:
        head, data = image["src"].split(",", 1)
        assert head == "data:image/png;base64"
        assert base64.b64decode(data)[:8] == PNG
    for _, attrs in page.attrs:
        for name, value in attrs.items():
            if name in ("src", "href", "action", "data", "srcset"):
                assert value.startswith("data:"), (name, value[:60])
    assert "http://" not in html and "https://" not in html and "url(" not in html
    return page
