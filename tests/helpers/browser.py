"""Headless Chromium through Selenium for the page tests, skipped (or failed under
``MOTIONTRACK_REQUIRE_DATA=1``) when the browser, its driver or the Python packages are
missing."""

from __future__ import annotations

import importlib.util
import os
import shutil

import pytest


def unavailable(msg: str) -> None:
    """Skip, or fail under MOTIONTRACK_REQUIRE_DATA=1 (where everything the suite needs must be
    present)."""
    if os.environ.get("MOTIONTRACK_REQUIRE_DATA") == "1":
        pytest.fail(msg + " and MOTIONTRACK_REQUIRE_DATA=1")
    pytest.skip(msg)


def browser_paths() -> tuple[str, str]:
    """Chromium's and chromedriver's paths (skips when either is missing)."""
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    driver = shutil.which("chromedriver") or (
        "/usr/bin/chromedriver" if os.access("/usr/bin/chromedriver", os.X_OK) else None)
    if not chromium or not driver:
        unavailable("chromium and chromedriver not found (Debian: apt-get install chromium "
                    "chromium-driver)")
    for module, extra in (("selenium", "dev"), ("starlette", "serve"), ("uvicorn", "serve")):
        if importlib.util.find_spec(module) is None:
            unavailable(f"{module} is not installed (pip install -e '.[{extra}]')")
    return chromium, driver


def chromium(window: str = "1400,1900"):
    """A headless Chromium WebDriver with the browser console logged (quit it when done)."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    binary, driver_path = browser_paths()
    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                f"--window-size={window}", "--hide-scrollbars"):
        options.add_argument(arg)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(service=Service(driver_path), options=options)
    driver.set_page_load_timeout(30)
    return driver
