"""The Filmstrip panel in a real browser: a LOCATE and a WHY made through
the page's server appear as thumbnails, the WHY marked as a failure; the
LOCATE's frame shows the parts it found, and Replay answers as the LOCATE
did with the same models, its parts drawn over the recorded ones; the live
overlay never takes a replay for the camera's latest result."""

from conftest import APP, click_css, wait_until
from test_page import click, ok_fields, select_tab


def test_the_filmstrip_shows_a_locate_and_replays_it(cell, browser):
    located = cell.say("LOCATE 1")
    found = int(ok_fields(located)[0])
    assert found == 4, located
    assert cell.say("WHY").startswith("OK ")
    select_tab(browser, "filmstrip")

    def films():
        click(browser, "filmstrip-refresh")
        return browser.js(
            "return Array.from(document.querySelectorAll('#filmstrip-list .film'))"
            ".map((f) => [Number(f.dataset.id), f.classList.contains('failed'),"
            " f.querySelector('figcaption').textContent])")

    shown = wait_until(lambda: (lambda f: f if len(f) >= 2 else None)(films()),
                       what="the LOCATE and the WHY in the filmstrip", interval=0.3)
    # Newest first: the WHY (a failure: someone asked why), then the LOCATE.
    (why_id, why_failed, why_text), (locate_id, locate_failed, locate_text) = shown[0], shown[1]
    assert why_failed and "WHY" in why_text
    assert not locate_failed
    assert locate_text == f"#{locate_id} LOCATE 1 \u2192 {located}"
    # Every thumbnail is a decoded image from the app's filmstrip.
    wait_until(lambda: browser.js(
        "return Array.from(document.querySelectorAll('#filmstrip-list img'))"
        ".every((i) => i.complete && i.naturalWidth === 160)"), what="the thumbnails")

    click_css(browser, f'#filmstrip-list .film[data-id="{locate_id}"]')
    recorded = wait_until(lambda: browser.js(
        "return document.querySelectorAll('#filmstrip-marks circle.recorded').length"),
        what="the recorded parts on the frame")
    assert recorded == found
    assert browser.js("return document.getElementById('filmstrip-frame').naturalWidth") == 640
    detail = browser.js("return document.getElementById('filmstrip-detail').textContent")
    assert f"< {located}" in detail
    # The frame the recorded reply's poses are in, as the app recorded it
    # (this cell has no calibration: vision pixels).
    assert f"< {located}\nreply in vision px (y up; no CALCAM yet)\n" in detail

    click(browser, "filmstrip-replay")
    reply = wait_until(lambda: browser.js(
        "return document.getElementById('filmstrip-replay-reply').dataset.reply"), what="the replay's reply")
    # The same frame, the same models: the same answer.
    assert reply == located
    replayed = wait_until(lambda: browser.js(
        "return document.getElementById('filmstrip-marks').dataset.replayed"), what="the replay's parts")
    assert int(replayed) == found
    # Drawn where the recorded ones are.
    centres = browser.js(
        "const c = (cls) => Array.from(document.querySelectorAll('#filmstrip-marks circle.' + cls))"
        ".map((e) => [Math.round(e.getAttribute('cx')), Math.round(e.getAttribute('cy'))]).sort();"
        "return [c('recorded'), c('replayed')];")
    assert centres[0] == centres[1]
    # The replay went to this panel alone, never the live view's result.
    assert browser.js(f"return window.picksight.latest['{APP}'].request") != "REPLAY"

    browser.js("document.getElementById('filmstrip-failures').click()")
    failures = wait_until(lambda: (lambda f: f if f and all(x[1] for x in f) else None)(
        browser.js("return Array.from(document.querySelectorAll('#filmstrip-list .film'))"
                   ".map((f) => [Number(f.dataset.id), f.classList.contains('failed')])")),
        what="failures only")
    assert [f[0] for f in failures] == [why_id]
    browser.screenshot("filmstrip")
    assert not browser.severe(), browser.severe()
    browser.js("document.getElementById('filmstrip-failures').click()")
    select_tab(browser, "live")
