"""The audit trail in the page, in a real browser: a change an engineer
makes appears, with that engineer's name, in the admin's Audit panel."""

import json
import urllib.request

from conftest import CAMERA, wait_until


def engineer_session(cell, name, password):
    """An HTTP client logged in as a new engineer (made by the admin)."""
    status, body = cell.http("POST", "/api/users", {"name": name, "role": "engineer", "password": password})
    assert status == 200, body
    opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())

    def post(path, payload):
        req = urllib.request.Request(cell.url + path, data=json.dumps(payload).encode(), method="POST",
                                     headers={"Content-Type": "application/json", "X-PickSight": "1"})
        with opener.open(req, timeout=10) as r:
            return r.status, json.loads(r.read())

    assert post("/api/login", {"user": name, "password": password})[0] == 200
    return post


def test_an_admin_sees_an_engineers_change_in_the_audit_panel(cell, browser):
    post = engineer_session(cell, "erik", "engineer-erik")
    parts = cell.json(f"/api/cameras/{CAMERA}/features")
    value = next(f["value"] for f in parts if f["name"] == "Parts")
    # The scene's own value again: recorded as a change, nothing moves.
    status, _ = post(f"/api/cameras/{CAMERA}/feature", {"name": "Parts", "value": value})
    assert status == 200
    browser.js("window.picksight.selectTab('audit')")

    def erik_row():
        rows = browser.js(
            "return Array.from(document.querySelectorAll('#audit-list tbody tr'))"
            ".map((r) => Array.from(r.cells).map((c) => c.textContent))")
        return next((r for r in rows if r[1] == "erik (engineer)" and r[3] == "camera.feature"), None)

    row = wait_until(lambda: erik_row() or browser.js("document.getElementById('audit-refresh').click()"),
                     what="the engineer's change in the Audit panel", interval=0.3)
    assert row[2] == "127.0.0.1"
    assert row[4] == CAMERA
    assert "Parts" in row[5]
    assert row[6].startswith("ok")
    assert row[7] == f"name=Parts value={value} \u2192 name=Parts value={value}"
    # The admin may export it.
    assert browser.js("return getComputedStyle(document.getElementById('audit-export')).display") != "none"
    browser.screenshot("audit")
    assert not browser.severe(), browser.severe()
    browser.js("window.picksight.selectTab('live')")
