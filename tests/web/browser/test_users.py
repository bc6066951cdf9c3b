"""Users in the page, in a real browser: the login form, an operator who
cannot teach, logout, and a session that ends while the page is open."""

import json

import pytest

from conftest import APP, Browser, Cell, bin_path, stdout_lines, wait_until


@pytest.fixture(scope="module")
def anonymous(cell, tmp_path_factory):
    """A browser on the page that has not logged in."""
    b = Browser(cell.url + "/", tmp_path_factory.mktemp("chromium-users"))
    yield b
    b.quit()


def command(browser, line):
    """One robot line through the page's own helper; its reply."""
    return browser.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "window.picksight.command(arguments[0]).then(done);", line)


def models(cell):
    return cell.say("MODELS").split()[1]


def test_login_with_a_wrong_then_the_right_password(cell, anonymous):
    wait_until(lambda: anonymous.js("return !document.getElementById('login').hidden"), what="the login form")
    # Nothing of the cell before the login.
    assert anonymous.js("return document.querySelectorAll('#camera-select option').length") == 0
    anonymous.login("admin", "not-the-password")
    wait_until(lambda: "wrong" in anonymous.js("return document.getElementById('login-error').textContent"),
               what="the refusal")
    assert not anonymous.logged_in()
    anonymous.login("admin", cell.admin_password)
    wait_until(anonymous.logged_in, what="the login")
    assert "admin" in anonymous.js("return document.getElementById('user-name').textContent")
    wait_until(lambda: anonymous.js("return document.querySelectorAll('#camera-select option').length") > 0,
               what="the camera list")


def test_an_operator_cannot_teach(cell, anonymous):
    status, body = cell.http("POST", "/api/users", {"name": "otto", "role": "operator", "password": "operator-otto"})
    assert status == 200, body
    anonymous.js("document.getElementById('logout').click()")
    anonymous.login("otto", "operator-otto")
    wait_until(anonymous.logged_in, what="the operator's login")
    assert "operator" in anonymous.js("return document.getElementById('user-name').textContent")
    # The page sends commands to the vision app it has chosen: on a loaded
    # machine that comes a moment after the login ("ERROR no vision app").
    wait_until(lambda: anonymous.js("return window.picksight.app"), what="the page's vision app")
    before = models(cell)
    reply = command(anonymous, "LEARN 7 taught AT 0 0 200 200")
    assert reply.startswith("ERROR"), reply
    assert "engineer" in reply, reply
    assert models(cell) == before
    # Locating is an operator's.
    assert not command(anonymous, "STATUS").startswith("ERROR")


def test_logout_ends_the_session(cell, anonymous):
    wait_until(anonymous.logged_in, what="a session")
    anonymous.js("document.getElementById('logout').click()")
    wait_until(lambda: anonymous.js("return !document.getElementById('login').hidden"), what="the login form")
    status = anonymous.driver.execute_async_script(
        "const done = arguments[arguments.length - 1];"
        "fetch('/api/cameras').then((r) => done(r.status));")
    assert status == 401


def test_a_session_ends_after_its_idle_time(cell, tmp_path_factory):
    web = cell._start([bin_path("picksight-web"), "--listen", "127.0.0.1:0", "--session-timeout", "2",
                       "--video-server", f"{cell.frames},{cell.control}",
                       "--vision-app", f"{APP},{cell.results},127.0.0.1:{cell.robot_port}"])
    lines = stdout_lines(web)
    b = Browser(lines["web"].strip() + "/", tmp_path_factory.mktemp("chromium-expiry"))
    try:
        b.login("admin", lines["admin-password"].strip())
        wait_until(b.logged_in, what="the login")
        # The page's own traffic keeps the session alive: the test waits
        # with the page quiet, then asks.
        b.js("window.picksight.user = window.picksight.user;")
        b.driver.execute_async_script(
            "const done = arguments[arguments.length - 1]; setTimeout(done, 3000);")
        b.js("window.picksight.get('/api/apps')")
        wait_until(lambda: "session ended" in b.js("return document.getElementById('login-error').textContent"),
                   what="the login form after expiry")
    finally:
        b.quit()
