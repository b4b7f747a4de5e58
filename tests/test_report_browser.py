"""The HTML report in a real browser (Debian's chromium, headless): its first screen at two
window sizes shows the title and the findings, and every figure it embeds loads. Screenshots
are kept under results/screenshots/ for a reader to open."""

from __future__ import annotations

import pytest
from browser import CHROMIUM, Browser
from workflow_copy import ROOT

REPORT = ROOT / "results" / "report.html"
SCREENSHOTS = ROOT / "results" / "screenshots"
SIZES = ((1366, 768), (1920, 1080))

pytestmark = [
    pytest.mark.skipif(
        CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)"
    ),
    pytest.mark.skipif(
        not REPORT.exists(),
        reason="no results/report.html: run snakemake -j2, then its --report",
    ),
]

# The landing page's title, once React has drawn it, and a heading's top by its text.
TITLE = "document.querySelector('.prose h1')"
HEADING = (
    "[...document.querySelectorAll('.prose h1')].find(h => h.textContent.trim() == '{}')"
    ".getBoundingClientRect().top"
)


@pytest.mark.parametrize(("width", "height"), SIZES)
def test_the_first_screen_shows_the_title_and_findings(width, height):
    with Browser(width, height) as browser:
        browser.open(REPORT.as_uri(), TITLE)
        top = browser.evaluate(f"{TITLE}.getBoundingClientRect().top")
        findings = browser.evaluate(HEADING.format("Findings"))
        tab = browser.evaluate("document.title")
        shot = browser.screenshot(SCREENSHOTS / f"landing-{width}x{height}.png")
    print(f"screenshot: {shot}")
    assert 0 <= top < height, f"the title is at {top} px, outside the {height} px window"
    assert findings < height, f"the findings start at {findings} px, below the first screen"
    assert "Snakemake" not in tab and "jointbench" in tab


def test_every_figure_loads():
    """Each output page the report embeds is opened the way the report does (an iframe), and
    every image on it must decode to a picture."""
    with Browser(1366, 768) as browser:
        browser.open(REPORT.as_uri(), TITLE)
        sizes = browser.evaluate(
            """(async () => {
              const out = {};
              for (const [path, r] of Object.entries(results)) {
                const html = await (await fetch(r.data_uri)).text();
                const doc = new DOMParser().parseFromString(html, 'text/html');
                for (const img of doc.querySelectorAll('img')) {
                  const image = new Image();
                  image.src = img.src;
                  try { await image.decode(); out[path] = image.naturalWidth; }
                  catch (e) { out[path] = 0; }
                }
              }
              return out;
            })()"""
        )
    assert sizes, "the report embeds no figure"
    broken = [path for path, width in sizes.items() if width < 100]
    assert not broken, f"figures that do not load: {broken}"
    print("figures loaded:", ", ".join(sorted(sizes)))
