"""The Users panel in a real browser: an admin adds an operator through it;
that operator, logged in, is not offered teaching, calibration nor the
panel, and the server refuses a LEARN anyway (403); the admin changes a
role, resets a password and removes a user, and cannot demote or remove
the last admin. Every one of these changes is in the audit trail."""

import json
import urllib.error
import urllib.request

import pytest

from conftest import APP, admin_browser, wait_until


@pytest.fixture(scope="module")
def page(cell, tmp_path_factory):
    """A browser that logs in through the page's form (not the fixture's
    session), as the admin first."""
    b = admin_browser(cell, tmp_path_factory.mktemp("chromium-users-panel"))
    yield b
    b.quit()


def shown(browser, selector):
    """Whether the element is displayed (not hidden by the role's CSS)."""
    return browser.js("const e = document.querySelector(arguments[0]);"
                      "return !!e && getComputedStyle(e).display !== 'none';", selector)


def listed_users(browser):
    """{name: role} as the Users panel's table shows them."""
    return browser.js(
        "const out = {};"
        "for (const r of document.querySelectorAll('#users-list tbody tr'))"
        "  out[r.dataset.user] = r.querySelector('select.user-role').value;"
        "return out;")


def unexpected_errors(browser):
    """The console's errors but the refusals these tests ask for (Chromium
    logs every 403 and 409 response as an error)."""
    return [e for e in browser.severe()
            if "status of 403" not in e["message"] and "status of 409" not in e["message"]]


def panel_reply(browser):
    return browser.js("return document.getElementById('users-reply').textContent")


def open_users_panel(browser):
    browser.js("document.querySelector('#tabs [data-tab=users]').click()")
    wait_until(lambda: "admin" in listed_users(browser), what="the users in the panel")


def fetch_status(browser, method, url, body=None):
    """The HTTP status of a request the page's own script makes (as the page
    sends a change: JSON and the X-PickSight header)."""
    return browser.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "const init = {method: arguments[0], credentials: 'same-origin', headers: {}};"
        "if (arguments[2] !== null) {"
        "  init.headers = {'Content-Type': 'application/json', 'X-PickSight': '1'};"
        "  init.body = JSON.stringify(arguments[2]);"
        "}"
        "fetch(arguments[1], init).then((r) => done(r.status), (e) => done(String(e)));",
        method, url, body)


def user_records(cell):
    return [r for r in cell.json("/api/audit?limit=1000")["records"]
            if r.get("action", "").startswith("user.")]


def login_status(cell, user, password):
    req = urllib.request.Request(cell.url + "/api/login", method="POST",
                                 data=json.dumps({"user": user, "password": password}).encode(),
                                 headers={"Content-Type": "application/json", "X-PickSight": "1"})
    try:
        with urllib.request.urlopen(req, timeout=10) as r:
            return r.status
    except urllib.error.HTTPError as e:
        return e.code


def test_an_admin_adds_an_operator_through_the_users_panel(cell, page):
    assert shown(page, "#tabs [data-tab=users]")
    open_users_panel(page)
    assert listed_users(page) == {"admin": "admin"}
    page.js("document.getElementById('user-add-name').value = 'olivia';"
            "document.getElementById('user-add-role').value = 'operator';"
            "document.getElementById('user-add-password').value = 'operator-olivia';"
            "document.getElementById('user-add').click();")
    wait_until(lambda: listed_users(page).get("olivia") == "operator", what="olivia in the list")
    # The password never stays in the form.
    assert page.js("return document.getElementById('user-add-password').value") == ""
    added = [r for r in user_records(cell) if r["action"] == "user.add" and r.get("target") == "olivia"]
    assert len(added) == 1, added
    assert added[0]["user"] == "admin" and added[0]["outcome"] == "ok"
    assert added[0]["after"] == {"role": "operator"}
    assert "operator-olivia" not in json.dumps(user_records(cell))
    page.screenshot("users-panel")
    assert not page.severe(), page.severe()


def test_the_operator_cannot_teach_nor_see_the_users_panel(cell, page):
    page.js("document.getElementById('logout').click()")
    page.login("olivia", "operator-olivia")
    wait_until(page.logged_in, what="the operator's login")
    assert "operator" in page.js("return document.getElementById('user-name').textContent")
    # Not offered: no Users, Teach nor Calibrate tab; the panels stay hidden
    # even when a script selects them.
    for tab in ("users", "teach", "calibrate"):
        assert not shown(page, f"#tabs [data-tab={tab}]"), tab
    assert shown(page, "#tabs [data-tab=live]")
    for tab in ("users", "teach"):
        page.js("window.picksight.selectTab(arguments[0])", tab)
        assert not shown(page, f"#panel-{tab}"), tab
    page.js("window.picksight.selectTab('live')")
    # Refused by the server whatever the page offers: teaching and the users.
    before = cell.say("MODELS")
    assert fetch_status(page, "POST", f"/api/apps/{APP}/command", {"line": "LEARN 7 AT 0 0 200 200"}) == 403
    assert cell.say("MODELS") == before
    assert fetch_status(page, "GET", "/api/users") == 403
    assert fetch_status(page, "POST", "/api/users/olivia/role", {"role": "admin"}) == 403
    # Watching and locating are an operator's.
    assert fetch_status(page, "POST", f"/api/apps/{APP}/command", {"line": "STATUS"}) == 200
    refused = [r for r in cell.json("/api/audit?limit=1000")["records"]
               if r.get("user") == "olivia" and r.get("outcome") == "refused"]
    assert any(r.get("arguments", {}).get("line", "").startswith("LEARN") for r in refused), refused
    page.screenshot("users-operator")
    page.js("document.getElementById('logout').click()")
    page.login("admin", cell.admin_password)
    wait_until(page.logged_in, what="the admin's login again")


def test_the_admin_changes_a_role_resets_a_password_and_removes_a_user(cell, page):
    open_users_panel(page)

    def row_js(user, script):
        page.js("const r = document.querySelector(`#users-list tbody tr[data-user='${arguments[0]}']`);" + script,
                user)

    row_js("olivia", "r.querySelector('select.user-role').value = 'engineer';"
                     "Array.from(r.querySelectorAll('button')).find((b) => b.textContent === 'Set role').click();")
    wait_until(lambda: listed_users(page).get("olivia") == "engineer", what="olivia an engineer")
    row_js("olivia", "r.querySelector('input.user-password').value = 'engineer-olivia';"
                     "Array.from(r.querySelectorAll('button')).find((b) => b.textContent === 'Reset').click();")
    wait_until(lambda: any(r["action"] == "user.password" for r in user_records(cell)), what="the reset")
    assert login_status(cell, "olivia", "operator-olivia") == 401
    assert login_status(cell, "olivia", "engineer-olivia") == 200

    # The last admin: refused with the server's reason, still an admin.
    row_js("admin", "r.querySelector('select.user-role').value = 'operator';"
                    "Array.from(r.querySelectorAll('button')).find((b) => b.textContent === 'Set role').click();")
    wait_until(lambda: "last admin" in panel_reply(page), what="the last admin's refusal")
    wait_until(lambda: listed_users(page).get("admin") == "admin", what="the list read again")
    row_js("admin", "const d = r.querySelector('button.user-delete'); d.click(); d.click();")
    wait_until(lambda: panel_reply(page).count("last admin") >= 2, what="the last admin's second refusal")
    assert cell.json("/api/users") == [{"name": "admin", "role": "admin"}, {"name": "olivia", "role": "engineer"}]

    # One click only arms Delete; the second removes.
    row_js("olivia", "r.querySelector('button.user-delete').click();")
    assert "olivia" in listed_users(page)
    row_js("olivia", "r.querySelector('button.user-delete').click();")
    wait_until(lambda: "olivia" not in listed_users(page), what="olivia removed")
    assert login_status(cell, "olivia", "engineer-olivia") == 401

    done = [(r["action"], r["target"], r["outcome"]) for r in user_records(cell)]
    done.reverse()  # oldest first
    assert done == [("user.add", "olivia", "ok"), ("user.role", "olivia", "ok"),
                    ("user.password", "olivia", "ok"), ("user.role", "admin", "error"),
                    ("user.delete", "admin", "error"), ("user.delete", "olivia", "ok")]
    page.screenshot("users-panel-changes")
    assert not unexpected_errors(page), unexpected_errors(page)
