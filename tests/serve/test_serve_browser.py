"""The live page of ``motiontrack serve`` in a real browser.

A ``motiontrack serve`` process runs on a free 127.0.0.1 port with two looping synthetic cameras
(scene files from ``motiontrack synth-events``) and a token; Debian's Chromium, headless, driven
by Selenium through ``chromedriver``, opens the page with ``?token=``, so every request the page
makes (stylesheet, script, API, MJPEG streams, Server-Sent Events, the editor's PUT) must pass the
token on or fail with 401.

Without ``chromium``/``chromedriver`` (Debian packages ``chromium`` and ``chromium-driver``;
``.ci/run`` installs them) or Selenium the tests skip, except under
``MOTIONTRACK_REQUIRE_DATA=1``, where they fail — as the tests that need real data do
(tests/helpers/data.py).

Screenshots a person can look at are written under each test's temporary folder
(``pytest --basetemp DIR`` keeps them in a known place).
"""

from __future__ import annotations

import json
import time

import pytest

from motiontrack.io.tomlfile import parse_toml
from motiontrack.types import EVENT_TYPES
from helpers.browser import browser_paths, chromium
from helpers.serve_process import ServeProcess, synth_cameras

pytestmark = pytest.mark.slow

TOKEN = "browser-test-token"
#: the two cameras: name -> synthetic scene (both cross their `gate` line in each loop)
CAMERAS = {"north": "synth:crossing?seed=1", "south": "synth:walker?seed=2"}
#: the longest a frame's event may take to reach the page's feed (seconds)
EVENT_LATENCY_S = 2.0


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    browser_paths()   # skip before starting anything when there is no browser
    root = tmp_path_factory.mktemp("serve")
    with ServeProcess(root, synth_cameras(root, CAMERAS), token=TOKEN) as srv:
        srv.wait_running(timeout=90)
        yield srv


@pytest.fixture(scope="module")
def browser(server):
    driver = chromium()
    try:
        yield driver
    finally:
        driver.quit()


@pytest.fixture
def page(server, browser):
    """The page, opened with the token, once both camera tiles show."""
    browser.get(f"{server.url}/?token={TOKEN}")
    for name in CAMERAS:
        server.wait(f"the tile of camera {name}",
                    lambda n=name: browser.find_elements("css selector",
                                                         f'[data-testid="camera-tile-{n}"]'),
                    timeout=15)
    yield browser
    errors = [e for e in browser.get_log("browser") if e["level"] == "SEVERE"]
    # a stream cut short while the page is left is not the page's fault; anything else is
    errors = [e for e in errors if "stream.mjpg" not in e["message"]]
    assert not errors, f"errors in the browser console: {errors}"
    # nothing the page did may have brought a camera down
    for name, cam in server.cameras().items():
        assert cam["status"] == "running" and cam["restarts"] == 0, (cam, server.logs())


def _js(driver, script: str, *args):
    return driver.execute_script(script, *args)


def _img_state(driver, name: str) -> dict:
    return _js(driver, """
        const img = document.querySelector(`[data-testid="camera-img-${arguments[0]}"]`);
        return {w: img.naturalWidth, h: img.naturalHeight, complete: img.complete};
    """, name)


def test_both_camera_pictures_update_with_their_numbers(server, page, tmp_path):
    shots = {}
    for name in CAMERAS:
        server.wait(f"camera {name}'s picture decoded", lambda n=name: _img_state(page, n)["w"] > 0,
                    timeout=15)
        img = page.find_element("css selector", f'[data-testid="camera-img-{name}"]')
        # each picture a second apart: the synthetic scenes carry sensor noise, so two frames
        # never look alike, and a frozen stream gives the same pixels twice
        first = img.screenshot_as_png
        frames_before = int(page.find_element("css selector",
                                              f'[data-testid="camera-frames-{name}"]').text)
        time.sleep(1.0)
        second = img.screenshot_as_png
        (tmp_path / f"{name}-1.png").write_bytes(first)
        (tmp_path / f"{name}-2.png").write_bytes(second)
        shots[name] = (first, second)
        assert first != second, f"camera {name}'s picture did not change in 1 s"
        state = _img_state(page, name)
        assert (state["w"], state["h"]) == (640, 480), state
        # the numbers: frames go up with the poll of /api/cameras, the status is the server's
        server.wait(f"camera {name}'s frame count rising",
                    lambda n=name: int(page.find_element(
                        "css selector", f'[data-testid="camera-frames-{n}"]').text) > frames_before,
                    timeout=5)
        assert page.find_element("css selector",
                                 f'[data-testid="camera-status-{name}"]').text == "running"
        fps = float(page.find_element("css selector", f'[data-testid="camera-fps-{name}"]').text)
        assert fps > 0
        assert page.find_element("css selector",
                                 f'[data-testid="camera-reconnects-{name}"]').text == "0"
    assert shots["north"][0] != shots["south"][0], "the two tiles show the same picture"
    page.save_screenshot(str(tmp_path / "page.png"))


def _feed(driver) -> list[dict]:
    """The feed's lines, top to bottom: the event and when the page received it (ms)."""
    return _js(driver, """
        return [...document.querySelectorAll('[data-testid="event"]')].map(li => ({
            ev: JSON.parse(li.dataset.event), received_ms: Number(li.dataset.receivedMs)}));
    """)


def _frame_read_time(ev: dict) -> float:
    """When the camera process read the frame that caused ``ev``: its ``wall`` (epoch seconds,
    the live API's stamp; the browser runs on the same machine, so on the same clock)."""
    assert "wall" in ev, f"a live event without its frame's wall-clock time: {ev}"
    return float(ev["wall"])


def test_events_reach_the_feed_within_two_seconds_of_their_frame(server, page, tmp_path):
    opened = time.time()

    def fresh_events_of_both():
        # only events of frames read after the page opened: events the server keeps from
        # before are not this page's latency
        evs = [e for e in _feed(page) if _frame_read_time(e["ev"]) > opened]
        return evs if {e["ev"]["camera"] for e in evs} == set(CAMERAS) else None

    # each loop of a synthetic camera (10 s at 25 fps) has its line crossings and zone entries
    events = server.wait("events of both cameras in the feed", fresh_events_of_both, timeout=40,
                         interval=0.5)
    page.save_screenshot(str(tmp_path / "feed.png"))
    latencies = [item["received_ms"] / 1000.0 - _frame_read_time(item["ev"]) for item in events]
    (tmp_path / "latency.json").write_text(json.dumps(
        [{**item["ev"], "latency_s": round(lat, 3)} for item, lat in zip(events, latencies)],
        indent=1))
    for item, latency in zip(events, latencies):
        ev = item["ev"]
        assert -0.05 <= latency <= EVENT_LATENCY_S, (ev, latency)
        # a looping camera's new play is announced by a discontinuity record in the feed
        assert ev["type"] in (*EVENT_TYPES, "discontinuity") and ev["camera"] in CAMERAS, ev
    # newest first: each camera's sequence numbers fall down the list
    for name in CAMERAS:
        seqs = [e["ev"]["seq"] for e in _feed(page) if e["ev"]["camera"] == name]
        assert seqs == sorted(seqs, reverse=True), seqs
    # the API has the same events under the same sequence numbers
    ev = events[0]["ev"]
    listed = server.get(f"/api/cameras/{ev['camera']}/events?since={ev['seq'] - 1}")
    assert listed and listed[0]["seq"] == ev["seq"] and listed[0]["type"] == ev["type"]


def _click_source_points(driver, points) -> None:
    """Click the editor's canvas at points given in the camera's source pixels.

    Each click is dispatched by the page's own script at the position the canvas has at that
    moment: the page reflows while it runs (its snapshot, its lists and messages), so a position
    WebDriver computed before moving its mouse can be stale by the time the mouse arrives."""
    canvas = driver.find_element("css selector", '[data-testid="editor-canvas"]')
    driver.execute_script("arguments[0].scrollIntoView({block: 'center'})", canvas)
    for x, y in points:
        driver.execute_script("""
            const c = arguments[0], r = c.getBoundingClientRect();
            const at = {clientX: r.left + arguments[1] * r.width / c.width,
                        clientY: r.top + arguments[2] * r.height / c.height,
                        bubbles: true, cancelable: true, view: window};
            c.dispatchEvent(new MouseEvent("mousemove", at));
            c.dispatchEvent(new MouseEvent("click", at));
        """, canvas, x, y)
        time.sleep(0.1)


def _listed(driver, kind: str) -> list[str]:
    """The names in the editor's list of ``kind`` (line or zone) items, read in one script: the
    page may render the list again between two WebDriver calls (a stale element)."""
    return _js(driver, "return [...document.querySelectorAll("
                       "`[data-testid^=\"editor-${arguments[0]}-name-\"]`)].map((e) => e.value)",
               kind)


def _count_row(driver, camera: str, line: str) -> dict | None:
    return _js(driver, """
        const row = document.querySelector(
            `table[data-camera="${arguments[0]}"] tr[data-kind="line"][data-name="${arguments[1]}"]`);
        return row ? {in: Number(row.dataset.in), out: Number(row.dataset.out)} : null;
    """, camera, line)


def test_a_line_drawn_in_the_editor_is_saved_and_counted(server, page, tmp_path):
    from selenium.webdriver.support.ui import Select

    name = "north"
    scene = server.get(f"/api/cameras/{name}/scene")
    w, h = scene["width"], scene["height"]
    Select(page.find_element("css selector", '[data-testid="editor-camera"]')).select_by_value(name)
    server.wait("the editor showing the scene's lines",
                lambda: len(page.find_elements("css selector",
                                               '[data-testid^="editor-line-name-"]'))
                == len(scene["lines"]) and _js(page, "return document.querySelector("
                                                   "'[data-testid=\"editor-canvas\"]').width") == w,
                timeout=10)

    # a name the scene file's schema refuses (blank): the page names the line and the key in the
    # schema's words and sends nothing
    schema = server.get("/api/schema/scene")
    pattern = schema["properties"]["line"]["items"]["properties"]["name"]["pattern"]
    before = (server.root / name / "scene.toml").read_bytes()
    _js(page, """
        const real = window.fetch;
        window.sceneWrites = 0;
        window.fetch = (url, options = {}) => {
          if (options.method === "PUT") window.sceneWrites += 1;
          return real(url, options);
        };
    """)
    _click_source_points(page, [(0.25 * w, 0.3 * h), (0.25 * w, 0.98 * h)])
    n = len(scene["lines"])
    blank = page.find_element("css selector", f'[data-testid="editor-line-name-{n}"]')
    blank.clear()
    blank.send_keys("  ")
    page.find_element("css selector", '[data-testid="editor-save"]').click()
    error = page.find_element("css selector", '[data-testid="editor-error"]')
    refusal = f"not saved: line {n + 1}: name must match the pattern {pattern}"
    server.wait("the schema's refusal shown",
                lambda: error.is_displayed() and error.text.startswith(refusal), timeout=10)
    assert _js(page, "return window.sceneWrites") == 0
    assert (server.root / name / "scene.toml").read_bytes() == before
    page.find_element("css selector", '[data-testid="editor-reload"]').click()
    server.wait("the unsaved line discarded",
                lambda: len(page.find_elements("css selector",
                                               '[data-testid^="editor-line-name-"]'))
                == len(scene["lines"]) and not error.is_displayed(), timeout=10)

    # a name the scene already has (the schema cannot say names are unique): the server refuses
    # the scene and the page shows its words
    page.find_element("css selector", '[data-testid="editor-name"]').send_keys("gate")
    _click_source_points(page, [(0.25 * w, 0.3 * h), (0.25 * w, 0.98 * h)])
    page.find_element("css selector", '[data-testid="editor-save"]').click()
    server.wait("the server's error shown", lambda: error.is_displayed() and "gate" in error.text,
                timeout=10)
    assert "400" in error.text
    # the refused PUT is the one error this page may log (reading the log empties it)
    logged = [e["message"] for e in page.get_log("browser") if e["level"] == "SEVERE"]
    assert all("/scene" in m and "400" in m for m in logged), logged
    assert "door" not in (server.root / name / "scene.toml").read_text()
    page.find_element("css selector", '[data-testid="editor-reload"]').click()
    server.wait("the unsaved line discarded",
                lambda: len(page.find_elements("css selector",
                                               '[data-testid^="editor-line-name-"]'))
                == len(scene["lines"]), timeout=10)

    # a vertical line left of the middle, over the feet of both walkers: both cross it each loop
    a, b = (0.4 * w, 0.3 * h), (0.4 * w, 0.98 * h)
    page.find_element("css selector", '[data-testid="editor-name"]').send_keys("door")
    _click_source_points(page, [a, b])
    names = _listed(page, "line")
    assert names == [line["name"] for line in scene["lines"]] + ["door"]
    page.find_element("css selector", '[data-testid="editor-save"]').click()
    server.wait("the scene saved",
                lambda: page.find_element(
                    "css selector", '[data-testid="editor-message"]').text.startswith("saved"),
                timeout=10)
    assert not page.find_element("css selector", '[data-testid="editor-error"]').is_displayed()

    # the camera's scene file now has the line, in source pixels (one displayed pixel of error)
    saved = parse_toml((server.root / name / "scene.toml").read_text(), "scene.toml")
    door = [line for line in saved["line"] if line["name"] == "door"]
    assert len(door) == 1
    px = w / _js(page, "return document.querySelector('[data-testid=\"editor-canvas\"]')"
                       ".getBoundingClientRect().width")
    for got, want in zip(door[0]["points"], (a, b)):
        assert got == pytest.approx(want, abs=1.5 * px)
    assert [z["name"] for z in saved["zone"]] == [z["name"] for z in scene["zones"]]

    # applied without a restart: the line shows in the counts and people crossing it count
    server.wait("the new line counted on the page",
                lambda: (c := _count_row(page, name, "door")) and c["in"] + c["out"] > 0,
                timeout=45, interval=0.5)
    counts = server.get(f"/api/cameras/{name}/counts")
    assert counts["lines"]["door"]["in"] + counts["lines"]["door"]["out"] > 0
    assert server.cameras()[name]["status"] == "running"
    page.save_screenshot(str(tmp_path / "editor.png"))


def test_a_zone_drawn_closes_with_enter_and_a_deleted_item_leaves_the_scene_file(server, page):
    from selenium.webdriver.common.keys import Keys
    from selenium.webdriver.support.ui import Select

    name = "south"
    scene = server.get(f"/api/cameras/{name}/scene")
    w, h = scene["width"], scene["height"]
    Select(page.find_element("css selector", '[data-testid="editor-camera"]')).select_by_value(name)
    server.wait("the editor showing the scene's zones",
                lambda: len(page.find_elements("css selector",
                                               '[data-testid^="editor-zone-name-"]'))
                == len(scene["zones"]), timeout=10)
    page.find_element("css selector", '[data-testid="tool-zone"]').click()
    page.find_element("css selector", '[data-testid="editor-name"]').send_keys("kerb")
    corners = [(0.05 * w, 0.6 * h), (0.25 * w, 0.6 * h), (0.25 * w, 0.9 * h), (0.05 * w, 0.9 * h)]
    _click_source_points(page, corners)
    page.find_element("css selector", '[data-testid="editor-canvas"]').send_keys(Keys.ENTER)
    names = _listed(page, "zone")
    assert names == [z["name"] for z in scene["zones"]] + ["kerb"]
    # the scene's line goes: its Delete button is labelled with its name
    gate = page.find_element("css selector", '[aria-label="Delete line gate"]')
    gate.click()
    page.find_element("css selector", '[data-testid="editor-save"]').click()
    server.wait("the scene saved",
                lambda: page.find_element(
                    "css selector", '[data-testid="editor-message"]').text.startswith("saved"),
                timeout=10)

    saved = parse_toml((server.root / name / "scene.toml").read_text(), "scene.toml")
    assert saved.get("line", []) == []
    kerb = [z for z in saved["zone"] if z["name"] == "kerb"]
    assert len(kerb) == 1
    px = w / _js(page, "return document.querySelector('[data-testid=\"editor-canvas\"]')"
                       ".getBoundingClientRect().width")
    assert len(kerb[0]["polygon"]) == 4
    for got, want in zip(kerb[0]["polygon"], corners):
        assert got == pytest.approx(want, abs=1.5 * px)
    # the camera runs the new scene: the zone is counted, the line no longer
    server.wait("the counts following the saved scene",
                lambda: (c := server.get(f"/api/cameras/{name}/counts"))
                and "kerb" in c["zones"] and "gate" not in c["lines"], timeout=15)


def test_items_in_metres_are_listed_and_saved_back_as_they_are(server, page):
    """A scene's lines and zones given in metres (``world``) have no pixels to draw: the editor
    lists them and sends them back unchanged with the scene it saves (the page's requests for
    the scene are answered here, as a camera with a calibration would have them)."""
    from selenium.webdriver.support.ui import Select

    name = "south"
    scene = server.get(f"/api/cameras/{name}/scene")
    far = {"name": "far", "world": [[1.5, 2.0], [3.0, 4.25]]}
    yard = {"name": "yard", "world": [[0, 0], [5, 0], [5, 5]], "loiter_s": 3}
    _js(page, """
        const [far, yard] = arguments, real = window.fetch;
        window.sentScenes = [];
        window.fetch = async (url, options = {}) => {
          // the camera's scene only, not the scene file's schema (api/schema/scene)
          if (!String(url).includes("/scene") || String(url).includes("api/schema/"))
            return real(url, options);
          if (options.method === "PUT") {
            window.sentScenes.push(JSON.parse(options.body));
            return new Response(options.body, {headers: {"content-type": "application/json"}});
          }
          const got = await (await real(url, options)).json();
          got.lines.push(far);
          got.zones.push(yard);
          return new Response(JSON.stringify(got), {headers: {"content-type": "application/json"}});
        };
    """, far, yard)
    Select(page.find_element("css selector", '[data-testid="editor-camera"]')).select_by_value(name)
    server.wait("the editor listing the items in metres too",
                lambda: _listed(page, "line") == [line["name"] for line in scene["lines"]] + ["far"],
                timeout=10)
    zone_names = _listed(page, "zone")
    assert zone_names == [z["name"] for z in scene["zones"]] + ["yard"]
    far_input = page.find_element("css selector",
                                  f'[data-testid="editor-line-name-{len(scene["lines"])}"]')
    assert "metres" in far_input.get_attribute("title")
    assert not page.find_element("css selector", '[data-testid="editor-error"]').is_displayed()
    page.find_element("css selector", '[data-testid="editor-save"]').click()
    server.wait("the scene sent", lambda: _js(page, "return window.sentScenes.length") == 1,
                timeout=10)
    (sent,) = _js(page, "return window.sentScenes")
    assert sent["lines"] == scene["lines"] + [far]
    assert sent["zones"] == scene["zones"] + [yard]
    logged = [e["message"] for e in page.get_log("browser") if e["level"] == "SEVERE"]
    assert logged == [], logged


def test_a_scene_file_the_camera_cannot_apply_is_shown_on_its_tile(server, page):
    """A hand edit of a scene file with a mistake: the camera keeps running with its last valid
    scene, and its tile says what is wrong until the file is valid again."""
    name = "north"
    path = server.root / name / "scene.toml"
    good = path.read_text()
    shown = f'[data-testid="camera-scene-error-{name}"]'
    assert not page.find_element("css selector", shown).is_displayed()
    path.write_text(good + "\n[[line]]\nname = 'door'\n")        # a line without points
    try:
        text = server.wait("the problem on the tile",
                           lambda: (e := page.find_element("css selector", shown)).is_displayed()
                           and e.text, timeout=15)
        assert text.startswith("scene not applied: scene file scene.toml: line[")
        assert "points" in text and "keeps its last valid scene" in text
    finally:
        path.write_text(good)
    server.wait("the problem gone from the tile",
                lambda: not page.find_element("css selector", shown).is_displayed(), timeout=15)
