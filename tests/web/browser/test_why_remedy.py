"""WHY's remedies in the page, in headless Chromium against a real cell: a
LOCATE whose regions one test refuses shows, beside each such region, the
tolerance that would accept it; the page's button applies it (TOLERANCE
through the page's session, then the same LOCATE) and the region is a part;
labels on a busy frame cover none of each other, and one under the mouse is
highlighted. The camera has no noise here: the frame the remedy was checked
on is the frame located again."""

import re

import pytest
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By

from conftest import SOURCE, Cell, wait_until
from test_page import locate_on_page, ok_fields, overlay_after, select_tab


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    c = Cell(tmp_path_factory.mktemp("data"), source=SOURCE + ",noise=0")
    yield c
    c.stop()


def latest(browser):
    return browser.js("return window.picksight.latest[window.picksight.app] || null")


def label_boxes(browser):
    """The screen rectangles of every label the overlay drew."""
    return browser.js("""
        return Array.from(document.querySelectorAll('#overlay .label, #overlay .reason')).map(t => {
            const r = t.getBoundingClientRect();
            return {text: t.textContent, left: r.left, top: r.top, right: r.right, bottom: r.bottom}; });""")


def overlapping(boxes):
    pairs = []
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            if a["left"] < b["right"] and b["left"] < a["right"] and a["top"] < b["bottom"] and b["top"] < a["bottom"]:
                pairs.append((a["text"], b["text"]))
    return pairs


def test_a_remedy_applied_from_the_page_makes_locate_accept_the_region(cell, browser):
    # Taught alone, then found among four of its kind.
    cell.set_parts(1)
    wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "1", what="one part on the table")
    assert cell.say("LEARN 1 ell").startswith("OK 1 ell"), "LEARN"
    cell.set_parts(4)
    wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "4", what="four parts on the table")
    # An edge tolerance finer than the pixel grid: the parts turned otherwise
    # than the taught one verify on too little of their boundary, refused
    # on that alone.
    assert cell.say("TOLERANCE 1 edge_tolerance_px 0.3").startswith("OK 1 ell")
    select_tab(browser, "live")
    reply, before = locate_on_page(browser, "1")
    assert reply.startswith("OK "), reply
    overlay = overlay_after(browser, before)
    refused = [r for r in overlay["rejections"] if r["test"] == "verify"]
    assert refused, overlay
    with_remedy = [r for r in refused if r["remedy"].startswith("verify_percent ")]
    assert with_remedy, refused
    target = with_remedy[0]
    # Beside the region: the remedy as a clickable line of its label, and the
    # same in the Live panel's list as a button.
    # (Read in one script: the overlay is drawn again as frames arrive.)
    remedy_lines = browser.js("""
        return Array.from(document.querySelectorAll(
            '#overlay .rejection[data-region="' + arguments[0] + '"] .remedy')).map(t => t.textContent);""",
        target["region"])
    assert remedy_lines == ["apply " + target["remedy"]], remedy_lines
    assert target["text"].endswith(", " + target["remedy"] + " would accept it"), target

    # A busy frame: the parts' labels and every reason, none covering another.
    boxes = label_boxes(browser)
    assert len(boxes) >= 4, boxes
    assert overlapping(boxes) == [], boxes
    # Hovered, a label is highlighted (bold) with its region: the mouse moved
    # onto the label's middle, the label under it read there.
    def hovered_weight():
        at = browser.js("""
            const t = document.querySelector('#overlay .rejection[data-region="' + arguments[0] + '"] .reason');
            const r = t.getBoundingClientRect();
            return [Math.round(r.left + r.width / 2), Math.round(r.top + r.height / 2)];""", target["region"])
        actions = ActionChains(browser.driver)
        actions.w3c_actions.pointer_action.move_to_location(at[0], at[1])
        actions.perform()
        return browser.js("""
            const e = document.elementFromPoint(arguments[0], arguments[1]);
            const t = e && e.closest('text');
            return t && t.classList.contains('reason') ? getComputedStyle(t).fontWeight : null;""", at[0], at[1])
    wait_until(lambda: hovered_weight() == "700", what="the hovered label highlighted")
    browser.screenshot("why-remedy")

    button = browser.driver.find_element(
        By.CSS_SELECTOR, f'#result-rejections button.remedy[data-region="{target["region"]}"]')
    assert button.text == "apply " + target["remedy"]
    before = {"request_id": overlay["request_id"], "line": "LOCATE 1"}
    button.click()
    # TOLERANCE went through the page's session, then the same LOCATE.
    wait_until(lambda: "> TOLERANCE 1 " + target["remedy"] in browser.driver.find_element(By.ID, "live-reply").text,
               what="the TOLERANCE line sent")
    after = overlay_after(browser, before)
    result = latest(browser)
    regions = [int(p.get("region", 0)) for p in result.get("parts", [])]
    assert target["region"] in regions, (target, result.get("parts"))
    assert all(r["region"] != target["region"] for r in after["rejections"]), after
    value = target["remedy"].split()[1]
    assert re.search(r" verify_percent=" + re.escape(value), cell.say("TOLERANCE 1")), value
    # Apart from each other, no part is said to touch another.
    assert not [b for b in label_boxes(browser) if "touching" in b["text"]]
    assert browser.severe() == []
