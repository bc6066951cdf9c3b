"""A real cell for the Python client's tests: picksight-video-server and
picksight-vision from the build tree (PICKSIGHT_BIN_DIR), on free ports,
with synthetic or file cameras. The package under test is the one the build
assembled (PYTHONPATH=build/python)."""

import os
import select
import subprocess
import time

import numpy as np
import pytest

BIN_DIR = os.environ.get("PICKSIGHT_BIN_DIR", "")
# How long a starting process may take to print its endpoints: generous,
# since a sanitizer build under a loaded CI machine starts several times
# slower, and a passing test never waits for the deadline.
START_TIMEOUT = 30.0


def bin_path(name):
    path = os.path.join(BIN_DIR, name)
    if not os.access(path, os.X_OK):
        pytest.fail(f"{path} not built (set PICKSIGHT_BIN_DIR to the build's bin/)")
    return path


class Process:
    """A child process whose stdout is read line by line with a deadline."""

    def __init__(self, argv):
        self.argv = argv
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL)
        self._buffer = b""

    def wait_line(self, prefix, timeout=10.0):
        """The rest of the first stdout line starting with `prefix`."""
        deadline = time.monotonic() + timeout
        fd = self.proc.stdout.fileno()
        while True:
            while b"\n" in self._buffer:
                line, self._buffer = self._buffer.split(b"\n", 1)
                text = line.decode(errors="replace")
                if text.startswith(prefix):
                    return text[len(prefix):]
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError(f"{self.argv[0]} printed no '{prefix}' line")
            ready, _, _ = select.select([fd], [], [], left)
            if ready:
                chunk = os.read(fd, 4096)
                if not chunk:
                    # Its stdout closed: it is exiting; waited for with a bound all the same.
                    try:
                        code = self.proc.wait(5)
                    except subprocess.TimeoutExpired:
                        code = "still running with its stdout closed"
                    raise RuntimeError(f"{self.argv[0]} exited: {code}")
                self._buffer += chunk

    def stop(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.proc.stdout.close()


# The servers are added to `started` as soon as they run, before their
# start lines are awaited: one that fails to start in time is stopped with
# the others instead of running on beside the next tests.
class VideoServer:
    def __init__(self, *args, started):
        self.process = Process([bin_path("picksight-video-server"), "--frames",
                                "tcp://127.0.0.1:*", "--control", "tcp://127.0.0.1:*", *args])
        started.append(self.process)
        self.frames = self.process.wait_line("frames ", START_TIMEOUT)
        self.control = self.process.wait_line("control ", START_TIMEOUT)


class Vision:
    def __init__(self, server, data_dir, started, camera="cam0"):
        self.process = Process([bin_path("picksight-vision"), "--frames", server.frames,
                                "--control", server.control, "--camera", camera,
                                "--robot-port", "0", "--bind", "127.0.0.1",
                                "--data-dir", str(data_dir)])
        started.append(self.process)
        self.port = int(self.process.wait_line("robot ", START_TIMEOUT))
        self.results = self.process.wait_line("results ", START_TIMEOUT)
        self.process.wait_line("ready", START_TIMEOUT)


@pytest.fixture
def cell_factory(tmp_path):
    """start(camera_args...) -> (VideoServer, Vision or None); all stopped at the end."""
    started = []

    def start(*server_args, vision=True):
        server = VideoServer(*server_args, started=started)
        app = None
        if vision:
            data = tmp_path / f"data{len(started)}"
            data.mkdir()
            app = Vision(server, data, started)
        return server, app

    yield start
    for p in reversed(started):
        p.stop()


@pytest.fixture
def synthetic_cell(cell_factory):
    """A trigger-mode synthetic camera cam0 (640x480, 4 parts) and a vision app."""
    return cell_factory("--source", "cam0=synthetic:width=640,height=480,parts=4,seed=3",
                        "--mode", "trigger")


class Scene:
    """The image file of a file camera, replaced atomically (the source
    re-reads it when its inode changes). Dark discs on a light background,
    drawn 4x larger and averaged down so their areas are exact enough for
    CALCAM."""

    SUPER = 4

    def __init__(self, directory, width=640, height=480):
        self.path = str(directory / "scene.pgm")
        self._next = str(directory / "next.pgm")
        self.width, self.height = width, height
        self.show([])

    def show(self, discs):
        """discs: (x, y, radius) in pixels, pixel centres at integers."""
        s = self.SUPER
        img = np.full((self.height, self.width), 200.0)
        for x, y, r in discs:
            # Coverage of each pixel of the disc's box, from s x s samples.
            x0, x1 = max(0, int(x - r) - 1), min(self.width, int(x + r) + 2)
            y0, y1 = max(0, int(y - r) - 1), min(self.height, int(y + r) + 2)
            ys, xs = np.mgrid[y0 * s : y1 * s, x0 * s : x1 * s]
            inside = ((xs + 0.5) / s - 0.5 - x) ** 2 + ((ys + 0.5) / s - 0.5 - y) ** 2 <= r * r
            cover = inside.reshape(y1 - y0, s, x1 - x0, s).mean(axis=(1, 3))
            img[y0:y1, x0:x1] -= cover * (200.0 - 40.0)
        with open(self._next, "wb") as f:
            f.write(b"P5\n%d %d\n255\n" % (self.width, self.height))
            f.write(np.round(img).astype(np.uint8).tobytes())
        os.replace(self._next, self.path)
