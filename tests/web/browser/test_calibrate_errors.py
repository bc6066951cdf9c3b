"""The Calibrate panel's refusals stay in sight, in headless Chromium
against a real cell: CALCAM that finds no single target, and the simulated robot's target
moved off the image (refused by the video server, no longer "OK"), are shown
on top of the panel in red and stay there through the STATUS and LIST
refreshes that follow, until the next button is pressed."""

from selenium.webdriver.common.by import By

from conftest import wait_until
from test_page import click, select_tab


def error_text(browser):
    return browser.js("const e = document.getElementById('cal-error'); return e.hidden ? '' : e.textContent")


def test_calibrate_errors_stay_on_top_in_red(cell, browser):
    select_tab(browser, "calibrate")
    click(browser, "cal-hide")
    wait_until(lambda: "hide target" in browser.driver.find_element(By.ID, "cal-reply").text, what="the hide")
    assert error_text(browser) == ""

    # CALCAM with parts on the table but no target: its refusal, then the
    # STATUS refresh above it in the log.
    click(browser, "cal-calcam")
    wait_until(lambda: "CALCAM" in error_text(browser), what="CALCAM's refusal on top")
    assert error_text(browser).startswith("CALCAM 5: ERROR 2 more than one target"), error_text(browser)
    wait_until(lambda: browser.driver.find_element(By.ID, "cal-reply").text.startswith("> STATUS"),
               what="the STATUS refresh after CALCAM")
    assert "CALCAM" in error_text(browser)
    placement = browser.js("""
        const e = document.getElementById('cal-error'), r = document.getElementById('cal-reply');
        return {colour: getComputedStyle(e).color, above: e.getBoundingClientRect().bottom <= r.getBoundingClientRect().top,
                first: e.previousElementSibling.tagName};""")
    assert placement["colour"] == "rgb(255, 69, 58)", placement
    assert placement["above"] and placement["first"] == "H2", placement
    browser.screenshot("calibrate-error")

    # The target moved off the image: refused by the video server, shown the same way.
    browser.js("""document.getElementById('cal-robot-x').value = '-12.5';
                  document.getElementById('cal-robot-y').value = '-600';""")
    click(browser, "cal-move")
    wait_until(lambda: "outside the image" in error_text(browser), what="the off-image refusal")
    assert error_text(browser).startswith("move target to robot -12.5 -600 mm: ERROR "), error_text(browser)

    # The next press clears it; a refresh that succeeds shows none.
    click(browser, "cal-list")
    wait_until(lambda: error_text(browser) == "", what="the refusal cleared")
    wait_until(lambda: "> LIST" in browser.driver.find_element(By.ID, "cal-reply").text, what="LIST")
    assert error_text(browser) == ""
    # The refused move is the one failed request (HTTP 400) in the console.
    unexpected = [e for e in browser.severe() if "/api/cameras/cam0/target" not in e.get("message", "")]
    assert unexpected == []
