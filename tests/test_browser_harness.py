"""The test browser (tests/browser.py) leaves nothing behind: every process Chromium started has
ended and its profile folder is gone when the browser closes, or a later test's cleanup races
a renderer still writing into it ("Directory not empty")."""

from __future__ import annotations

from pathlib import Path

import pytest
from browser import CHROMIUM, Browser, processes

pytestmark = pytest.mark.skipif(
    CHROMIUM is None, reason="chromium is not installed (apt-get install chromium)"
)


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid``."""
    parents = {child: parent for child, (_, parent, _) in processes().items()}
    found, frontier = set(), {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


def _running(pid: int) -> bool:
    """Whether ``pid`` exists and is not a zombie waiting to be reaped."""
    state = processes().get(pid)
    return state is not None and state[0] != "Z"


@pytest.mark.parametrize("page", ["about:blank", "data:text/html,<h1>x</h1>"] * 3)
def test_closing_the_browser_ends_every_process_it_started_and_removes_its_profile(page):
    with Browser(800, 600) as browser:
        browser.open(page, "document.body")
        started = {browser.pid} | _descendants(browser.pid)
        profile = Path(browser.profile)
    assert len(started) > 1  # Chromium runs helper processes: the test must see them
    assert not [pid for pid in started if _running(pid)]
    assert not profile.exists()
