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
    wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "4", what="four parts on the table")
    assert cell.say("LEARN 1 ell").startswith("OK 1 ell"), "LEARN"
    # An area tolerance below the pixel grid's differences between parts
    # turned otherwise: the other parts are the taught one at another size,
    # refused on their area alone.
    assert cell.say("TOLERANCE 1 area_tolerance 0.0001").startswith("OK 1 ell")
    select_tab(browser, "live")
    reply, before = locate_on_page(browser, "1")
    assert reply.startswith("OK "), reply
    overlay = overlay_after(browser, before)
    refused = [r for r in overlay["rejections"] if r["test"] in ("area", "scale")]
    assert refused, overlay
    with_remedy = [r for r in refused if r["remedy"].startswith("area_tolerance ")]
    assert with_remedy, refused
    target = with_remedy[0]
    # Beside the region: the remedy as a clickable line of its label, and the
    # same in the Live panel's list as a button.
    remedy_lines = browser.driver.find_elements(
        By.CSS_SELECTOR, f'#overlay .rejection[data-region="{target["region"]}"] .remedy')
    assert len(remedy_lines) == 1 and remedy_lines[0].text == "apply " + target["remedy"]
    assert target["text"].endswith(", " + target["remedy"] + " would accept it"), target

    # A busy frame: the parts' labels and every reason, none covering another.
    boxes = label_boxes(browser)
    assert len(boxes) >= 4, boxes
    assert overlapping(boxes) == [], boxes
    # Hovered, a label is highlighted (bold) with its region.
    label = browser.driver.find_element(
        By.CSS_SELECTOR, f'#overlay .rejection[data-region="{target["region"]}"] .reason')
    ActionChains(browser.driver).move_to_element(label).perform()
    wait_until(lambda: browser.js("return getComputedStyle(arguments[0]).fontWeight", label) == "700",
               what="the hovered label highlighted")
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
    assert re.search(r" area_tolerance=" + re.escape(value), cell.say("TOLERANCE 1")), value
    # Apart from each other, no part is said to touch another.
    assert not [b for b in label_boxes(browser) if "touching" in b["text"]]
    assert browser.severe() == []
