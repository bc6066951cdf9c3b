"""The examples under python/examples run against a real cell."""

import os
import subprocess
import sys

EXAMPLES = os.path.join(os.path.dirname(__file__), "..", "..", "python", "examples")


def run_example(name, *args):
    return subprocess.run([sys.executable, os.path.join(EXAMPLES, name), *args],
                          capture_output=True, text=True, timeout=60)


def test_locate_example(synthetic_cell):
    _, vision = synthetic_cell
    r = run_example("locate.py", "--port", str(vision.port), "1")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("4 parts of type 1 (vision-px frame)")
    assert len(r.stdout.splitlines()) == 5


def test_watch_frames_and_camera_info_examples(cell_factory, tmp_path):
    server, _ = cell_factory("--source", "cam0=synthetic:width=320,height=240,parts=2",
                             "--mode", "freerun", "--fps", "20", vision=False)
    r = run_example("watch_frames.py", "--frames", server.frames, "--camera", "cam0",
                    "--count", "3")
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert len(lines) == 4
    assert lines[0].startswith("cam0 #") and "(240, 320)" in lines[0]
    assert lines[-1].startswith("received=3 ")

    out = tmp_path / "cam0.pgm"
    r = run_example("camera_info.py", "--control", server.control, "--snap", "cam0",
                    "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("cam0: synthetic:")
    assert out.read_bytes().startswith(b"P5\n320 240\n255\n")
    r = run_example("camera_info.py", "--control", server.control, "--snap", "nosuch")
    assert r.returncode == 1 and "UNKNOWN_CAMERA" in r.stderr
