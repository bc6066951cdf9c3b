"""A real cell for the page's browser tests (video server with a synthetic
camera, vision app, picksight-web on port 0, all from the build tree) and a
headless Chromium on its page. One cell and one browser for the module: the
tests run in file order and each leaves the cell as it found it."""

import importlib.util
import json
import os
import time
import urllib.error
import urllib.request
from pathlib import Path

import pytest
from selenium import webdriver
from selenium.webdriver.chrome.service import Service

HERE = Path(__file__).resolve().parent
ASSETS = os.environ.get("PICKSIGHT_WEB_ASSETS", str(HERE.parents[2] / "web" / "assets"))
ARTIFACTS = Path(os.environ.get("PICKSIGHT_ARTIFACTS", "web_browser_artifacts"))

# The Python client tests' child-process helpers (stdout read line by line
# with a deadline), loaded from their file rather than copied.
_spec = importlib.util.spec_from_file_location("picksight_python_cell", HERE.parents[1] / "python" / "conftest.py")
_cell = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_cell)
Process = _cell.Process
bin_path = _cell.bin_path

CAMERA = "cam0"
APP = "vision0"
# A static scene (the synthetic camera's noise makes every frame differ):
# four L-shaped parts of one type apart from each other, and the simulated
# robot of the demo cell for the calibration panel.
SOURCE = (f"{CAMERA}=synthetic:width=640,height=480,parts=4,types=l_shape,size=90,seed=7,"
          "mm_per_px=0.25,rz=178.7,dx=330.5,dy=-612.25,target_radius=5")


# A JavaScript function for browser.js scripts: the page's frame image drawn
# on a canvas, {img, width, height, data} (RGBA bytes), or null while it has
# not loaded.
FRAME_PIXELS_JS = """
    function framePixels() {
        const img = document.getElementById('frame');
        if (!img.complete || !img.naturalWidth) return null;
        const c = document.createElement('canvas');
        c.width = img.naturalWidth; c.height = img.naturalHeight;
        const g = c.getContext('2d');
        g.drawImage(img, 0, 0);
        return {img: img, width: c.width, height: c.height,
                data: g.getImageData(0, 0, c.width, c.height).data};
    }
"""


def wait_until(condition, timeout=30.0, what="condition", interval=0.05):
    """Polls `condition` until it returns something truthy; that value."""
    deadline = time.monotonic() + timeout
    last = None
    while time.monotonic() < deadline:
        try:
            last = condition()
        except Exception as e:  # the page may not be ready yet
            last = e
        if last and not isinstance(last, Exception):
            return last
        time.sleep(interval)
    raise AssertionError(f"timed out waiting for {what} (last: {last!r})")


def click_css(browser, css, timeout=10.0):
    """Clicks the element `css` selects. A panel's list is drawn again when a
    refresh it started returns, so an element found a moment before may be
    replaced by its copy: the click then goes to the copy."""
    from selenium.common.exceptions import StaleElementReferenceException
    from selenium.webdriver.common.by import By

    def attempt():
        try:
            browser.driver.find_element(By.CSS_SELECTOR, css).click()
            return True
        except StaleElementReferenceException:
            return False

    wait_until(attempt, timeout=timeout, what=f"a click on {css}")


def stdout_lines(process, until="ready", timeout=20.0):
    """Every stdout line of a starting process up to `until`, as
    {first word: rest of the line}."""
    found = {}
    deadline = time.monotonic() + timeout
    while True:
        line = process.wait_line("", max(0.1, deadline - time.monotonic()))
        word, _, rest = line.partition(" ")
        found[word] = rest
        if word == until:
            return found


class Cell:
    """The running processes and their endpoints."""

    def __init__(self, data_dir, source=SOURCE):
        self.processes = []
        self.data_dir = Path(data_dir)  # the vision app's: models/type_<N>.yaml
        server = self._start([bin_path("picksight-video-server"), "--source", source,
                              "--frames", "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*"])
        lines = stdout_lines(server)
        self.frames, self.control = lines["frames"], lines["control"]
        vision = [bin_path("picksight-vision"), "--frames", self.frames, "--control", self.control,
                  "--camera", CAMERA, "--robot-port", "0", "--bind", "127.0.0.1",
                  "--data-dir", str(data_dir)]
        vision += ["--name", APP, "--results-bind", "tcp://127.0.0.1:*"]
        lines = stdout_lines(self._start(vision))
        self.robot_port = int(lines["robot"])
        self.results = lines["results"]
        web = self._start([bin_path("picksight-web"), "--listen", "127.0.0.1:0", "--assets", ASSETS,
                           "--video-server", f"{self.frames},{self.control}",
                           "--vision-app", f"{APP},{self.results},127.0.0.1:{self.robot_port}"])
        # With no users yet, picksight-web makes 'admin' and prints its
        # password once, before its URL.
        lines = stdout_lines(web)
        self.url = lines["web"].strip()
        self.admin_password = lines["admin-password"].strip()
        self.opener = urllib.request.build_opener(urllib.request.HTTPCookieProcessor())
        status, body = self.http("POST", "/api/login", {"user": "admin", "password": self.admin_password})
        assert status == 200, body

    def _start(self, argv):
        p = Process(argv)
        self.processes.append(p)
        return p

    def stop(self):
        for p in reversed(self.processes):
            p.stop()

    # HTTP, as the page uses it.
    def http(self, method, path, body=None):
        data = None if body is None else json.dumps(body).encode()
        # What the page sends: a change needs JSON and the X-PickSight header.
        headers = {"Content-Type": "application/json", "X-PickSight": "1"} if data else {}
        req = urllib.request.Request(self.url + path, data=data, method=method, headers=headers)
        try:
            with self.opener.open(req, timeout=10) as r:
                return r.status, r.read()
        except urllib.error.HTTPError as e:
            return e.code, e.read()

    def json(self, path):
        status, body = self.http("GET", path)
        assert status == 200, f"GET {path}: {status} {body[:200]!r}"
        return json.loads(body)

    def camera(self):
        return next(c for c in self.json("/api/cameras") if c["name"] == CAMERA)

    def say(self, line):
        """One robot-protocol line through picksight-web."""
        status, body = self.http("POST", f"/api/apps/{APP}/command", {"line": line})
        assert status == 200, f"{line}: {status} {body[:200]!r}"
        return json.loads(body)["reply"]

    def set_parts(self, n):
        status, body = self.http("POST", f"/api/cameras/{CAMERA}/feature", {"name": "Parts", "value": str(n)})
        assert status == 200, body


@pytest.fixture(scope="module")
def cell(tmp_path_factory):
    c = Cell(tmp_path_factory.mktemp("data"))
    yield c
    c.stop()


class Browser:
    """Headless Chromium on the page; the browser console is collected."""

    def __init__(self, url, profile):
        options = webdriver.ChromeOptions()
        options.binary_location = "/usr/bin/chromium"
        for arg in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                    "--window-size=1500,950", "--hide-scrollbars", f"--user-data-dir={profile}"):
            options.add_argument(arg)
        # The MJPEG stream and the event stream never finish loading.
        options.page_load_strategy = "none"
        options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        self.driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
        self.console = []
        self.driver.get(url)

    def login(self, user, password):
        """Logs in through the page's form; waits until the form is gone."""
        wait_until(lambda: self.js("return !document.getElementById('login').hidden"), what="the login form")
        self.js("document.getElementById('login-user').value = arguments[0];"
                "document.getElementById('login-password').value = arguments[1];"
                "document.getElementById('login-submit').click();", user, password)

    def logged_in(self):
        return self.js("return document.getElementById('login').hidden && !!window.picksight.user")

    def js(self, script, *args):
        return self.driver.execute_script(script, *args)

    def logs(self):
        self.console += self.driver.get_log("browser")
        return self.console

    def severe(self):
        return [e for e in self.logs() if e.get("level") == "SEVERE"]

    def screenshot(self, name):
        ARTIFACTS.mkdir(parents=True, exist_ok=True)
        path = ARTIFACTS / f"{name}.png"
        self.driver.save_screenshot(str(path))
        return path

    def quit(self):
        self.driver.quit()


def admin_browser(cell, profile):
    """A browser on `cell`'s page, logged in through its form as the admin."""
    b = Browser(cell.url + "/", profile)
    b.login("admin", cell.admin_password)
    wait_until(b.logged_in, what="the admin's login")
    return b


@pytest.fixture(scope="module")
def browser(cell, tmp_path_factory):
    b = admin_browser(cell, tmp_path_factory.mktemp("chromium"))
    yield b
    b.quit()
