"""The review page's timeline: how long a day of 1,000 events takes to show in a browser.

A store of ``--events`` events (default 1,000) of 4 cameras spread over one day (the day before
this run) is written with :class:`motiontrack.io.event_store.EventStore`; ``motiontrack serve
--review`` serves it on a free 127.0.0.1 port, and headless Chromium (Selenium 4, Debian's
``chromium`` and ``chromedriver``) opens the page ``--rounds`` times. Each round reports the time
from the start of the navigation (``performance.timeOrigin``) until the timeline holds a mark for
every event, measured in the page itself; median and range, beside the target of 1 s.

Run: .venv/bin/python benchmarks/review_page.py [--events 1000] [--rounds 5]
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

from motiontrack.io.event_store import EventStore

TARGET_S = 1.0
TYPES = ("line_cross", "zone_enter", "zone_exit", "loiter", "abandoned")


def fill(path: Path, n: int, day_start: float, seed: int = 0) -> None:
    rng = random.Random(seed)
    with EventStore(path) as store:
        for k in range(n):
            kind = rng.choice(TYPES)
            event = {"type": kind, "frame": k + 1, "track": rng.randrange(300),
                     ("line" if kind == "line_cross" else "zone"): rng.choice(("gate", "bench"))}
            store.add(event, rng.choice(("gate", "lobby", "yard", "lot")),
                      day_start + 86400.0 * (k + 0.5) / n, "seg")
        store.close(finished=True)


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver") or "/usr/bin/chromedriver"
    if not chromium or not os.access(driver, os.X_OK):
        raise SystemExit("needs chromium and chromedriver (Debian: apt-get install chromium "
                         "chromium-driver)")
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                "--window-size=1400,1000"):
        options.add_argument(arg)
    return webdriver.Chrome(service=Service(driver), options=options)


def shown_after(driver, url: str, n: int, timeout: float = 60.0) -> float:
    """Seconds from the navigation's start until the page shows ``n`` marks."""
    driver.get("about:blank")
    driver.get(url)
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        t = driver.execute_script(
            "return document.querySelectorAll('[data-testid=\"event-mark\"]').length >= "
            f"{n} ? (window.__shown = window.__shown || performance.now()) : null;")
        if t is not None:
            return float(t) / 1000.0
        time.sleep(0.01)
    raise SystemExit(f"the page did not show {n} marks in {timeout:g} s")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=1000)
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    now = time.localtime()
    day_start = time.mktime((now.tm_year, now.tm_mon, now.tm_mday - 1, 0, 0, 0, 0, 0, -1))
    with tempfile.TemporaryDirectory() as tmp:
        fill(Path(tmp) / "events.db", args.events, day_start)
        port = _port()
        with open(Path(tmp) / "review.log", "wb") as log:
            proc = subprocess.Popen([sys.executable, "-m", "motiontrack", "serve", "--review", tmp,
                                     "--port", str(port)], stdout=log, stderr=subprocess.STDOUT)
            driver = None
            try:
                url = f"http://127.0.0.1:{port}/"
                for _ in range(300):
                    try:
                        urllib.request.urlopen(url + "api/events/search?limit=1", timeout=2)
                        break
                    except OSError:
                        time.sleep(0.1)
                driver = _browser()
                times = [shown_after(driver, url, args.events) for _ in range(args.rounds)]
            finally:
                if driver is not None:
                    driver.quit()
                proc.terminate()
                proc.wait(10)
    med = statistics.median(times)
    print(f"review page, {args.events} events of one day in 4 cameras, {args.rounds} loads in "
          "headless Chromium")
    print(f"{'':<28} {'median s':>9} {'min s':>7} {'max s':>7} {'target s':>9}")
    print(f"{'timeline shown':<28} {med:>9.3f} {min(times):>7.3f} {max(times):>7.3f} "
          f"{TARGET_S:>9.1f}")
    return 0 if med < TARGET_S else 1


if __name__ == "__main__":
    raise SystemExit(main())
