"""The review page (``motiontrack serve --review RUN``) in a real browser: a tracked run's
events as marks on a timeline, each with its snapshot and clip, filtered by type."""

from __future__ import annotations

import os
import subprocess
import sys
import time
import urllib.request

import pytest

from helpers import free_port
from helpers.browser import browser_paths, chromium
from motiontrack.io.event_store import EventStore

pytestmark = pytest.mark.slow

TOKEN = "review-token"


@pytest.fixture
def review(scene_runs, tmp_path):
    """``serve --review`` over the shared run of synth:runner (its events and evidence)."""
    browser_paths()
    run = scene_runs("runner", 0).run_dir
    port = free_port()
    env = {k: v for k, v in os.environ.items() if k != "MOTIONTRACK_TOKEN"}
    with open(tmp_path / "review.log", "wb") as log:
        proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "serve", "--review",
                                 str(run), "--port", str(port), "--token", TOKEN], stdout=log,
                                stderr=subprocess.STDOUT, env=env)
        url = f"http://127.0.0.1:{port}"
        try:
            end = time.monotonic() + 30
            while True:
                try:
                    urllib.request.urlopen(f"{url}/api/events/search?token={TOKEN}", timeout=2)
                    break
                except OSError:
                    if proc.poll() is not None or time.monotonic() > end:
                        pytest.fail((tmp_path / "review.log").read_text())
                    time.sleep(0.1)
            yield run, url
        finally:
            proc.terminate()
            proc.wait(10)


def _marks(driver):
    return driver.find_elements("css selector", '[data-testid="event-mark"]')


def _until(what, check, timeout=15.0):
    end = time.monotonic() + timeout
    while not (result := check()):
        if time.monotonic() > end:
            pytest.fail(f"not within {timeout:g} s: {what}")
        time.sleep(0.1)
    return result


def test_the_review_page_shows_each_event_with_its_snapshot_and_clip(review):
    from selenium.webdriver.support.ui import Select

    run, url = review
    with EventStore(run, readonly=True) as store:
        events = list(store)
    driver = chromium()
    try:
        driver.get(f"{url}/?token={TOKEN}")
        marks = _until("a mark per event", lambda: (m := _marks(driver)) and len(m) == len(events)
                       and m)
        assert sorted(int(m.get_attribute("data-id")) for m in marks) == [e.id for e in events]
        first = next(m for m in marks if int(m.get_attribute("data-id")) == events[0].id)
        driver.execute_script("arguments[0].dispatchEvent(new MouseEvent('click'))", first)
        for image in ("event-snapshot", "event-object", "event-clip"):
            _until(f"{image} shown", lambda i=image: driver.execute_script(
                f"const i = document.querySelector('[data-testid=\"{i}\"]');"
                "return !!i && !i.hidden && i.naturalWidth > 0;"))
        shown = driver.find_element("css selector", '[data-testid="event-json"]').text
        assert f'"frame": {events[0].frame}' in shown
        kinds = {e.type for e in events}
        kind = sorted(kinds)[0]
        Select(driver.find_element("css selector", '[data-testid="review-type"]')) \
            .select_by_value(kind)
        _until("only the marks of one type",
               lambda: len(_marks(driver)) == sum(e.type == kind for e in events))
        # The totals table is filled by its own request and replaced whole, so it is read in
        # one script call and waited for rather than read row by row after the marks.
        _until("the totals of that type", lambda: driver.execute_script(
            "return [...document.querySelectorAll('[data-testid=\"review-totals\"] tbody tr')]"
            ".reduce((n, r) => n + Number(r.cells[3].textContent), 0);")
            == sum(e.type == kind for e in events))
        errors = [e for e in driver.get_log("browser") if e["level"] == "SEVERE"
                  and "clip.mjpg" not in e["message"]]
        assert not errors, errors
    finally:
        driver.quit()
