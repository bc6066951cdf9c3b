"""A photograph taught and located from the HMI alone, in headless Chromium
against a real cell whose camera is the photograph (a file: camera): the
sweets of tests/data/scenes/smarties.png. A rectangle dragged round one
sweet, Teach and Save, then LOCATE 1 on the Live tab: every whole sweet is
drawn on the page where it lies (the centres read off the photograph by eye,
as in tests/vision_app/photographs_e2e_test.cpp)."""

import os

import pytest

from conftest import CAMERA, Cell, admin_browser, wait_until
from test_page import check_overlay_matches, drag_a_rectangle, locate_on_page, overlay_after, poses, \
    select_tab, teach_on_page

DATA = os.environ.get("PICKSIGHT_TEST_DATA_DIR",
                      os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "data"))
SWEETS = os.path.join(DATA, "scenes", "smarties.png")
# Every whole sweet (the three the frame's edge cuts are not whole).
WHOLE_SWEETS = [(377, 81), (269, 117), (205, 211), (287, 213), (347, 238), (33, 228), (98, 259),
                (152, 271), (219, 306), (294, 320), (134, 327)]


@pytest.fixture(scope="module")
def sweets(tmp_path_factory):
    c = Cell(tmp_path_factory.mktemp("sweets"), source=f"{CAMERA}=file:{SWEETS}")
    yield c
    c.stop()


@pytest.fixture(scope="module")
def sweets_browser(sweets, tmp_path_factory):
    b = admin_browser(sweets, tmp_path_factory.mktemp("chromium-sweets"))
    yield b
    b.quit()


def test_every_whole_sweet_from_one_taught_in_the_page(sweets, sweets_browser):
    browser = sweets_browser
    camera = wait_until(lambda: (lambda c: c if c.get("width") == 413 else None)(sweets.camera()),
                        what="the photograph's frames")
    select_tab(browser, "teach")
    # Round the green sweet in the upper middle, as a person drags it.
    _, rect = drag_a_rectangle(browser, camera, "teach", (236, 85), (300, 149))
    browser.js("""document.getElementById('teach-name').value = 'sweet';""")
    reply = teach_on_page(browser)
    assert reply.startswith("OK 1 sweet"), reply
    select_tab(browser, "live")
    reply, before = locate_on_page(browser, "1")
    found = [(x, -y) for x, y, _ in poses(reply)]
    assert len(found) == len(WHOLE_SWEETS), reply
    for sx, sy in WHOLE_SWEETS:
        assert any(abs(x - sx) <= 5 and abs(y - sy) <= 5 for x, y in found), (reply, (sx, sy))
    check_overlay_matches(sweets, browser, reply, overlay_after(browser, before))
    browser.screenshot("photograph-sweets")
    assert browser.severe() == []
