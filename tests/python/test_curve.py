"""CURVE from Python against a real video server with an allow-list: the
listed client gets frames and control replies, an unlisted key gets
nothing in the same time, and key files are checked as the C++ tools do."""

import os
import time
import subprocess

import pytest

from conftest import bin_path
from picksight import CameraControl, ControlTimeout, CurveKeys, FrameSubscriber


def keygen(directory, name):
    subprocess.run([bin_path("picksight-keygen"), name, "--dir", str(directory)], check=True,
                   stdout=subprocess.DEVNULL)
    return str(directory / f"{name}.key"), str(directory / f"{name}.key_secret")


def test_listed_key_gets_frames_and_control_and_others_nothing(cell_factory, tmp_path):
    keys = tmp_path / "keys"
    clients = keys / "clients"
    clients.mkdir(parents=True)
    server_public, server_secret = keygen(keys, "server")
    listed_public, listed_secret = keygen(keys, "listed")
    _, stranger_secret = keygen(keys, "stranger")
    os.replace(listed_public, clients / "listed.key")
    server, _ = cell_factory("--source", "cam0=synthetic:width=320,height=240,parts=2,seed=5",
                             "--fps", "20", "--curve-secret-key", server_secret,
                             "--curve-clients", str(clients), vision=False)

    listed = CurveKeys(server_public, listed_secret)
    stranger = CurveKeys(server_public, stranger_secret)
    # The frames come sealed on a plain socket: the stranger and the plain
    # subscriber receive them but cannot open them (the stranger is refused
    # the key on the control socket).
    with FrameSubscriber(server.frames, "cam0", curve=listed, control=server.control) as good, \
            FrameSubscriber(server.frames, "cam0", curve=stranger,
                            control=server.control) as bad, \
            FrameSubscriber(server.frames, "cam0") as plain:
        frame = good.receive(timeout=10)
        assert frame is not None and frame.image.shape == (240, 320)
        # Frames keep coming to the listed client; within that time the
        # others received none.
        for _ in range(5):
            assert good.receive(timeout=5) is not None
        assert good.malformed == 0
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and (bad.unopened == 0 or plain.malformed == 0):
            assert bad.receive(timeout=0.2) is None
            assert plain.receive(timeout=0.2) is None
        # Under a key it was not given: counted apart, not as malformed.
        assert bad.received == 0 and bad.unopened > 0 and bad.malformed == 0
        assert plain.received == 0 and plain.malformed > 0
    with pytest.raises(ValueError, match="control endpoint"):
        FrameSubscriber(server.frames, "cam0", curve=listed)

    with CameraControl(server.control, curve=listed) as control:
        assert [c.name for c in control.list_cameras()] == ["cam0"]
    with CameraControl(server.control, timeout=1.0, curve=stranger) as control:
        with pytest.raises(ControlTimeout):
            control.list_cameras()


def test_key_files_are_checked(tmp_path):
    public, secret = keygen(tmp_path, "k")
    os.chmod(secret, 0o640)
    with pytest.raises(PermissionError, match="chmod 600"):
        CurveKeys(public, secret)
    os.chmod(secret, 0o600)
    # The public file where the secret one belongs (private, but no secret).
    misplaced = tmp_path / "misplaced.key_secret"
    misplaced.write_bytes(open(public, "rb").read())
    os.chmod(misplaced, 0o600)
    with pytest.raises(ValueError, match="secret-key"):
        CurveKeys(public, str(misplaced))
    garbage = tmp_path / "garbage.key"
    garbage.write_text("not a key\n")
    with pytest.raises(ValueError, match="garbage.key"):
        CurveKeys(str(garbage))
    keys = CurveKeys(public)  # a fresh pair of its own
    assert len(keys.public) == 40 and len(keys.secret) == 40
