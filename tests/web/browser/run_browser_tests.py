"""Runs the browser tests with pytest, or exits 77 (CTest's skip) when
headless Chromium cannot be driven here: no chromium, no chromedriver or no
python3-selenium."""

import importlib.util
import os
import shutil
import sys

SKIP = 77


def missing():
    if not shutil.which("chromium") and not os.access("/usr/bin/chromium", os.X_OK):
        return "chromium"
    if not os.access("/usr/bin/chromedriver", os.X_OK):
        return "chromium-driver (/usr/bin/chromedriver)"
    if importlib.util.find_spec("selenium") is None:
        return "python3-selenium"
    return None


if __name__ == "__main__":
    absent = missing()
    if absent:
        print(f"web_browser: skipped, {absent} is not installed (deploy/install-deps.sh)")
        sys.exit(SKIP)
    import pytest

    here = os.path.dirname(os.path.abspath(__file__))
    sys.exit(pytest.main(["-q", "-p", "no:cacheprovider", here] + sys.argv[1:]))
