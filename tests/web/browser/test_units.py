"""Units and frames on the page's numbers, in headless Chromium against a
real cell of its own (no model, no calibration at first): the Live table's
image columns say sensor pixels with y down, the reply's columns and caption
name the frame the result's reply_frame says (vision px before any
calibration, robot mm after it) and hold the reply's own numbers; a region
with no model shows no score and no grasp style; the Teach, Vision, Camera
and Calibrate panels carry their units. Each check fails when the label it
reads is taken away."""

import pytest
from selenium.webdriver.common.by import By

from conftest import APP, ARTIFACTS, Cell, wait_until
from test_page import click, locate_on_page, ok_fields, overlay_after, select_tab


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    c = Cell(tmp_path_factory.mktemp("data"))
    yield c
    c.stop()


def header_texts(browser, table):
    return browser.js("""return Object.fromEntries(Array.from(document.querySelectorAll(
        '#' + arguments[0] + ' thead th[data-col]')).map(th => [th.dataset.col, th.textContent.trim()]));""", table)


def table_rows(browser, table):
    return browser.js("""return Array.from(document.querySelectorAll('#' + arguments[0] + ' tbody tr')).map(
        r => Array.from(r.cells).map(c => c.textContent));""", table)


def latest_result(cell):
    return cell.json(f"/api/results/{APP}/latest")


def reply_poses(reply, typed):
    """LOCATE's poses as [(type, x, y, rz)]; type None for LOCATE <type>."""
    f = ok_fields(reply)
    n, size = int(f[0]), 4 if typed else 3
    out = []
    for i in range(n):
        g = [float(v) for v in f[1 + size * i:1 + size * (i + 1)]]
        out.append((int(g[0]), *g[1:]) if typed else (None, *g))
    return out


def check_reply_columns(rows, reply, typed):
    """The reply columns hold the reply's poses, in its order."""
    poses = reply_poses(reply, typed)
    offered = [r for r in rows if r[5] != "not offered"]
    assert len(offered) == len(poses), (rows, reply)
    for row, (_, x, y, rz) in zip(offered, poses):
        # One decimal on the page, three in the reply.
        assert (float(row[6]), float(row[7]), float(row[8])) == pytest.approx((x, y, rz), abs=0.051), (row, reply)


def check_frame_shown(browser, cell, frame, words):
    """The caption names the latest result's reply_frame, the reply
    columns' header carries its unit."""
    assert latest_result(cell).get("reply_frame") == frame
    shown = browser.js("return document.getElementById('result-frame').dataset.frame")
    assert shown == frame
    caption = browser.driver.find_element(By.ID, "result-units").text
    assert words in caption and "sensor pixels" in caption and "y down" in caption, caption
    headers = header_texts(browser, "result-parts")
    assert headers["reply"] == f"reply: {words}" and headers["reply-rz"] == "rz \u00b0", headers
    assert words in browser.driver.find_element(By.ID, "result-summary").text


def test_live_table_says_pixels_and_the_reply_frame(cell, browser):
    """No model: every region is reported with type -1, at its own pose, in
    vision px (y up): the image columns are pixels with y down, the reply's
    y is the image's negated; no score, no grasp style for such a region."""
    select_tab(browser, "live")
    reply, before = locate_on_page(browser, "ALL")
    regions = int(ok_fields(reply)[0])
    assert regions >= 1, reply
    overlay_after(browser, before)
    headers = header_texts(browser, "result-parts")
    assert headers["image"] == "image: px, y down" and headers["angle"] == "angle \u00b0", headers
    titles = browser.js("""return Array.from(document.querySelectorAll('#result-parts thead th[data-col]')).map(
        th => th.dataset.col + ': ' + th.title).join('\\n')""")
    assert "y DOWN" in titles and "clockwise" in titles and "counter-clockwise" in titles, titles
    check_frame_shown(browser, cell, "pixels", "vision px")
    rows = table_rows(browser, "result-parts")
    assert len(rows) == regions, rows
    for row in rows:
        assert row[0] == "-1 no model" and row[1] == "-", row
        assert row[5] == "own pose", row
        # vision px is the image with y up: the reply's y is the image's negated.
        assert float(row[6]) == pytest.approx(float(row[2]), abs=0.11), row
        assert float(row[7]) == pytest.approx(-float(row[3]), abs=0.11), row
    text = browser.driver.find_element(By.ID, "result-parts").text
    assert "style -1" not in text, text
    check_reply_columns(rows, reply, typed=True)
    assert browser.severe() == []


def test_panels_carry_their_units(cell, browser):
    """Areas in px², symmetry in degrees, the frame size and ROI in px, the
    calibration's vision columns in px before CALCAM."""
    stat = browser.driver.find_element(By.ID, "stat-size").text
    assert stat.endswith(" px"), stat
    assert browser.driver.find_element(By.ID, "stat-roi").text.endswith(" px")
    cell.set_parts(1)
    try:
        wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "1", what="one part on the table")
        assert cell.say("LEARN 1 single").startswith("OK 1 single")
    finally:
        cell.set_parts(4)
    select_tab(browser, "teach")
    wait_until(lambda: browser.js("return document.querySelector('#models-list tr[data-type=\"1\"]')"),
               what="the model in the list")
    models = browser.js("return Array.from(document.querySelectorAll('#models-list thead th')).map(t => t.textContent)")
    assert "area px\u00b2" in models and "symmetry \u00b0" in models, models
    wait_until(lambda: browser.js(
        "return Array.from(document.querySelectorAll('#panel-teach .grasp-unit')).every(e => e.textContent === 'px')"),
        what="the grasp fields in px before CALCAM")
    select_tab(browser, "vision")
    labels = browser.driver.find_element(By.ID, "panel-vision").text
    assert "min area px\u00b2" in labels and "min hole area px\u00b2" in labels, labels
    select_tab(browser, "calibrate")
    wait_until(lambda: header_texts(browser, "cal-points").get("vision-x") == "vision x px",
               what="the vision columns in px before CALCAM")
    assert "sensor px" in browser.driver.find_element(By.ID, "cal-units").text
    assert browser.severe() == []


def test_live_table_after_calibration_says_robot_mm(cell, browser):
    """A taught type located: its score shown; after the simulated cell's
    calibration the reply is in robot mm, and the page says so beside the
    same image pixels."""
    select_tab(browser, "live")
    reply, before = locate_on_page(browser, "1")
    assert reply.startswith("OK "), reply
    overlay_after(browser, before)
    rows = table_rows(browser, "result-parts")
    assert rows and all(r[0] == "1 single" and 0 < float(r[1]) <= 1 and r[5] == "own pose" for r in rows), rows
    check_frame_shown(browser, cell, "pixels", "vision px")

    select_tab(browser, "calibrate")
    browser.js("document.getElementById('cal-sim-points').value = '4'")
    wait_until(lambda: browser.js("return document.getElementById('cal-simulate').offsetParent !== null"),
               what="the simulated robot's buttons")
    click(browser, "cal-simulate")
    wait_until(lambda: len(browser.driver.find_elements(By.CSS_SELECTOR, "#cal-points tbody tr")) == 4 and
               browser.js("return !document.getElementById('cal-simulate').disabled"),
               timeout=60, what="four stored points")
    assert "frame=robot" in cell.say("STATUS")
    assert header_texts(browser, "cal-points")["vision-x"] == "vision x mm"
    assert browser.driver.find_element(By.ID, "cal-vision-unit").text == "mm"
    # The image's points have negative vision y (y up the image).
    assert all(float(r[2]) < 0 for r in table_rows(browser, "cal-points"))
    cell.set_parts(4)  # the calibration emptied the table
    wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "4", what="the parts back on the table")

    select_tab(browser, "live")
    reply, before = locate_on_page(browser, "1")
    assert reply.startswith("OK ") and not reply.startswith("OK 0"), reply
    overlay_after(browser, before)
    check_frame_shown(browser, cell, "robot_mm", "robot mm")
    rows = table_rows(browser, "result-parts")
    check_reply_columns(rows, reply, typed=False)
    # Every column in view: the table fits the panel's width.
    assert browser.js("const w = document.querySelector('#panel-live .scroll-x');"
                      "return w.scrollWidth <= w.clientWidth") is True
    browser.screenshot("live-units")
    # The panel alone (docs/web-live-units.png is this screenshot).
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    browser.driver.find_element(By.ID, "panels").screenshot(str(ARTIFACTS / "live-units-panel.png"))
    assert browser.severe() == []
