"""The Teach panel cannot lose work, in headless Chromium against a real
cell: the type defaults to the next free one; a name LEARN would refuse is
refused in the page; Teach only shows what would be learned and found
(the model's outline drawn on the part);
saving over an existing type asks first, and without the confirmation the
model file stays byte for byte as it was; confirmed it is replaced; Undo puts
the file back byte for byte; a part taught again as a second type is
flagged as looking like the first."""

from selenium.webdriver.common.by import By

from conftest import wait_until
from test_page import click, ok_fields, select_tab


def model_file(cell, type_):
    path = cell.data_dir / "models" / f"type_{type_}.yaml"
    return path.read_bytes() if path.exists() else None


def text(browser, element_id):
    return browser.driver.find_element(By.ID, element_id).text


def type_field(browser):
    return browser.js("return document.getElementById('teach-type').value")


def type_in(browser, element_id, value):
    """Types into a field as a person does (the field becomes the user's)."""
    field = browser.driver.find_element(By.ID, element_id)
    field.clear()
    field.send_keys(value)


def preview(browser):
    """Teach, then the preview's text once it shows."""
    browser.js("document.getElementById('teach-preview').dataset.reply = '';")
    click(browser, "teach-button")
    wait_until(lambda: browser.js("return !document.getElementById('teach-preview').hidden"),
               what="the TRYLEARN preview")
    return text(browser, "teach-preview-text")


def last_reply(browser):
    return browser.js("return document.getElementById('teach-reply').dataset.lastReply || ''")


def answer_confirmation(browser, accept):
    """The page's confirm() dialog: its text, accepted or dismissed."""
    alert = wait_until(lambda: browser.driver.switch_to.alert, what="the confirmation")
    message = alert.text
    if accept:
        alert.accept()
    else:
        alert.dismiss()
    return message


def test_teach_flow_confirms_replacing_and_undo_restores(cell, browser):
    cell.set_parts(1)
    try:
        wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "1", what="one part on the table")
        browser.js("window.picksight.rect.teach = null; window.picksight.drawTool();")
        select_tab(browser, "teach")
        # No model yet: type 1. One taught elsewhere (a robot): the next free.
        wait_until(lambda: type_field(browser) == "1", what="type 1 by default")
        assert cell.say("LEARN 1 first").startswith("OK 1 first")
        click(browser, "models-refresh")
        wait_until(lambda: type_field(browser) == "2", what="the next free type")
        first = model_file(cell, 1)
        assert first

        # A name LEARN would refuse: said in the page, nothing sent.
        type_in(browser, "teach-name", "my part")
        wait_until(lambda: "space" in text(browser, "teach-name-error"), what="the name's error")
        browser.js("window.picksight.sent = [];")
        browser.js("const log = window.picksight.log;"
                   "window.picksight.log = (line, reply) => { window.picksight.sent.push(line); log(line, reply); };")
        click(browser, "teach-button")
        wait_until(lambda: "the name holds a space" in last_reply(browser), what="the refusal")
        assert browser.js("return window.picksight.sent") == []
        assert browser.js("return document.getElementById('teach-preview').hidden")

        # The same part as type 2: the preview flags it as type 1's look-alike.
        type_in(browser, "teach-name", "copy")
        shown = preview(browser)
        assert "would find 1 of type 2" in shown, shown
        assert "has no model yet" in shown, shown
        warnings = text(browser, "teach-warnings")
        assert "looks like type 1 (first)" in warnings, warnings
        assert any(line.startswith("TRYLEARN 2 copy") for line in browser.js("return window.picksight.sent"))
        assert model_file(cell, 2) is None  # tried, not stored
        # Its outline on the part, from the results stream (TRYLEARN's parts).
        wait_until(lambda: browser.js("""
            const r = window.picksight.latest[window.picksight.app];
            const o = document.getElementById('overlay');
            return r && (r.request_line || '').startsWith('TRYLEARN 2 copy') && o.dataset.parts === '1' &&
                   o.querySelectorAll('path.outline').length === 1;"""), what="the tried model's outline on the image")
        click(browser, "teach-cancel")

        # Over type 1: the preview says what it replaces; Save asks first.
        type_in(browser, "teach-type", "1")
        type_in(browser, "teach-name", "second")
        shown = preview(browser)
        assert "Saving replaces type 1 'first'" in shown, shown
        browser.screenshot("teach-preview")
        click(browser, "teach-save")
        message = answer_confirmation(browser, accept=False)
        assert "Replace model 1 'first'" in message, message
        wait_until(lambda: "model 1 'first' kept" in text(browser, "teach-reply"), what="not sent")
        assert model_file(cell, 1) == first
        assert not any(line.startswith("LEARN") for line in browser.js("return window.picksight.sent"))
        assert cell.say("MODELS").startswith("OK 1 1 first ")

        # Confirmed: replaced.
        click(browser, "teach-save")
        answer_confirmation(browser, accept=True)
        wait_until(lambda: last_reply(browser).startswith("OK 1 second"), what="the LEARN reply")
        assert model_file(cell, 1) != first
        assert cell.say("MODELS").startswith("OK 1 1 second ")
        # Saved: the type field is the next free one again.
        wait_until(lambda: type_field(browser) == "2", what="the next free type after saving")

        # Undo: the first model's file back, byte for byte, and in use.
        click(browser, "teach-undo")
        wait_until(lambda: last_reply(browser).startswith("OK 1 restored"), what="the UNDO reply")
        assert "undid: LEARN 1 second" in last_reply(browser)
        assert model_file(cell, 1) == first
        assert cell.say("MODELS").startswith("OK 1 1 first ")
        wait_until(lambda: browser.js(
            "return document.querySelector('#models-list tr[data-type=\"1\"] td:nth-child(2)').textContent") == "first",
            what="the model list after Undo")
        browser.screenshot("teach-undo")
    finally:
        cell.say("FORGET 1")
        cell.set_parts(4)
    assert browser.severe() == []


def test_add_view_reads_the_part_again_and_undo_takes_it_back(cell, browser):
    """A model's Add view sends LEARNVIEW <type> (AT the rectangle when one
    is drawn) and shows how many views the model has; the file keeps the
    readings; Undo takes the view back byte for byte."""
    cell.set_parts(1)
    try:
        wait_until(lambda: ok_fields(cell.say("BLOBS"))[0] == "1", what="one part on the table")
        browser.js("window.picksight.rect.teach = null; window.picksight.drawTool();")
        select_tab(browser, "teach")
        assert cell.say("LEARN 1 bracket").startswith("OK 1 bracket")
        taught = model_file(cell, 1)
        click(browser, "models-refresh")
        button = "#models-list tr[data-type=\"1\"] button.model-view"
        wait_until(lambda: browser.js(f"return !!document.querySelector('{button}')"), what="the Add view button")
        browser.js(f"document.querySelector('{button}').click()")
        wait_until(lambda: last_reply(browser).startswith("OK 1 bracket 2 "), what="the LEARNVIEW reply")
        wait_until(lambda: not browser.js("return document.getElementById('teach-preview').hidden"),
                   what="the views shown")
        assert "2 views" in text(browser, "teach-preview-text")
        # Where the view was read: the model's outline on the part.
        wait_until(lambda: browser.js("""
            const r = window.picksight.latest[window.picksight.app];
            const o = document.getElementById('overlay');
            return r && (r.request_line || '').startsWith('LEARNVIEW 1') && o.dataset.parts === '1' &&
                   o.querySelectorAll('path.outline').length === 1;"""), what="the part the view read, outlined")
        assert b"views:" in model_file(cell, 1)
        # Stored already: no Save offered.
        assert browser.js("return document.getElementById('teach-save').hidden")
        browser.screenshot("teach-add-view")
        click(browser, "teach-undo")
        wait_until(lambda: last_reply(browser).startswith("OK 1 restored"), what="the UNDO reply")
        assert "undid: LEARNVIEW 1" in last_reply(browser)
        assert model_file(cell, 1) == taught
    finally:
        cell.say("FORGET 1")
        cell.set_parts(4)
    assert browser.severe() == []
