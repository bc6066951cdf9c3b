"""The Jobs panel in headless Chromium against a real cell: the cell saved
as a job, another model taught, the job loaded back (the app's models are
the job's again); a job exported as a download whose bytes are the job
file's, imported under another name from a file input (sent in pieces,
recorded once in the audit trail) and loadable; a damaged file refused on
import and nothing stored."""

import json

from selenium.webdriver.common.by import By

from conftest import Cell, click_css, wait_until
from test_page import click, ok_fields, select_tab

import pytest


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    c = Cell(tmp_path_factory.mktemp("data"))
    yield c
    c.stop()


def listed(browser):
    return browser.js("return Array.from(document.querySelectorAll('#jobs-list tbody tr'))"
                      ".map((r) => r.dataset.job)")


def last_reply(browser):
    return browser.js("return document.getElementById('jobs-reply').textContent.split('\\n')[1] || ''")


def models(cell):
    """The type numbers MODELS lists."""
    fields = ok_fields(cell.say("MODELS"))
    return [int(fields[1 + 5 * i]) for i in range(int(fields[0]))]


# The page's latest result is the load, and nothing is drawn.
CLEARED_BY_LOAD = """
    const r = window.picksight.latest[window.picksight.app];
    return r && (r.request_line || '').startsWith('JOB LOAD 1-bracket') &&
           document.getElementById('overlay').dataset.parts === '0';"""


def row_button(browser, job, action):
    click_css(browser, f'#jobs-list tr[data-job="{job}"] .job-{action}')


def test_jobs_panel_saves_loads_exports_and_imports(cell, browser, tmp_path):
    cell.set_parts(1)
    wait_until(lambda: cell.say("LEARN 1 bracket").startswith("OK 1 bracket "), what="LEARN of one part")
    select_tab(browser, "jobs")
    browser.js("document.getElementById('jobs-name').value = '1-bracket'")
    click(browser, "jobs-save")
    wait_until(lambda: "1-bracket" in listed(browser), what="the saved job in the list")
    assert last_reply(browser).startswith("< OK 1-bracket 1 "), last_reply(browser)
    job_file = cell.data_dir / "jobs" / "1-bracket.job"
    assert job_file.exists()

    # Another model in force; Load brings the job's back.
    assert cell.say("FORGET 1") == "OK"
    assert cell.say("LEARN 4 other").startswith("OK 4 other ")
    assert models(cell) == [4]
    # A LOCATE's part drawn before the load...
    assert cell.say("LOCATE ALL").startswith("OK 1 4 ")
    wait_until(lambda: browser.js("return document.getElementById('overlay').dataset.parts") == "1",
               what="the part found with the other model drawn")
    row_button(browser, "1-bracket", "load")
    wait_until(lambda: last_reply(browser).startswith("< OK 1-bracket "), what="the JOB LOAD reply")
    assert models(cell) == [1]
    # ...is no longer drawn once the job is loaded: it was found with
    # models and settings that are not in force.
    wait_until(lambda: browser.js(CLEARED_BY_LOAD), what="the overlay cleared by the load")
    wait_until(lambda: browser.js("return document.getElementById('jobs-current').textContent") == "1-bracket",
               what="the job in force")

    # Export: the download holds the job file's bytes.
    browser.js("window.picksight.lastExport = null")
    row_button(browser, "1-bracket", "export")
    exported = wait_until(lambda: browser.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "const b = window.picksight.lastExport;"
        "if (!b) { done(null); return; }"
        "b.arrayBuffer().then((a) => done(Array.from(new Uint8Array(a))));"), what="the export")
    assert bytes(exported) == job_file.read_bytes()

    # Import that file under another name from the file input.
    copy = tmp_path / "copy.job"
    copy.write_bytes(bytes(exported))
    browser.driver.find_element(By.ID, "jobs-file").send_keys(str(copy))
    click(browser, "jobs-import")
    wait_until(lambda: "copy" in listed(browser), what="the imported job in the list", timeout=60)
    assert last_reply(browser).startswith("< OK copy 1 "), last_reply(browser)
    assert (cell.data_dir / "jobs" / "copy.job").read_bytes() == job_file.read_bytes()
    assert cell.say("JOB LOAD copy").startswith("OK copy 1 ")
    # One record for the import, not one per piece, without the base64.
    records = json.loads(cell.http("GET", "/api/audit?limit=1000")[1])["records"]
    imports = [r for r in records if str(r.get("arguments", {}).get("line", "")).startswith("JOB IMPORT copy")]
    assert len(imports) == 1, imports
    assert len(imports[0]["arguments"]["line"]) < 80, imports[0]
    assert imports[0]["outcome"] == "ok"

    # A damaged file: refused, nothing stored.
    broken = tmp_path / "broken.job"
    broken.write_bytes(bytes(exported)[: len(exported) // 2])
    browser.driver.find_element(By.ID, "jobs-file").send_keys(str(broken))
    click(browser, "jobs-import")
    wait_until(lambda: last_reply(browser).startswith("< ERROR 51 "), what="the refusal", timeout=60)
    assert "broken" not in listed(browser)
    assert not (cell.data_dir / "jobs" / "broken.job").exists()
    browser.screenshot("jobs")
    assert not browser.severe(), browser.severe()
