"""CameraControl's hardware trigger mode on a camera that has an input:
Aravis's fake GigE camera behind a real video server. The fake camera has no
wired line, so its trigger source "Software", fired with its TriggerSoftware
command, stands in for the pulse a robot's digital output would send. Run
alone (ctest python_aravis): the fake camera answers on a fixed port."""

import os
import subprocess
import time

import pytest

from conftest import VideoServer
from picksight import CameraControl, ControlError, FrameSubscriber
from picksight import picksight_pb2 as pb

FAKE_CAMERA = os.environ.get("ARV_FAKE_GV_CAMERA", "arv-fake-gv-camera-0.8")


@pytest.fixture
def fake_camera_server():
    fake = subprocess.Popen([FAKE_CAMERA, "-i", "127.0.0.1"], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    started = []
    try:
        server = VideoServer("--source", "cam0=aravis:Aravis-Fake-GV01", "--fps", "10", started=started)
        with CameraControl(server.control, timeout=10.0) as control:
            # Generous: a loaded machine is slow to start the fake camera.
            deadline = time.monotonic() + 60
            while control.describe("cam0").summary.state != "streaming":
                assert time.monotonic() < deadline, "the fake camera never streamed"
                time.sleep(0.1)
        yield server
    finally:
        for process in started:
            process.stop()
        fake.kill()
        fake.wait()


def test_hardware_trigger_waits_for_the_pulse(fake_camera_server):
    server = fake_camera_server
    with CameraControl(server.control, timeout=10.0) as control:
        control.set_hardware_trigger("cam0", line="Software", activation="", timeout=1.5)
        assert control.hardware_trigger("cam0") == {
            "mode": "hardware", "line": "Software", "activation": "", "timeout": 1.5}
        # The camera's thread applies the mode after the reply: poll for it.
        deadline = time.monotonic() + 30
        while control.get_feature("cam0", "TriggerMode").value != "On":
            assert time.monotonic() < deadline, "TriggerMode never switched on"
            time.sleep(0.05)
        ticket = control.trigger_ticket("cam0")
        assert ticket.mode == pb.HARDWARE_TRIGGER and not ticket.triggered
        assert (ticket.trigger_line, ticket.trigger_timeout_ms) == ("Software", 1500)

        # No pulse: the snap says so after the trigger timeout.
        with pytest.raises(ControlError) as e:
            control.snap("cam0", timeout=30)
        assert "no hardware trigger on Software" in e.value.text

        # A ticket, then pulses: the frame with the ticket's number comes
        # from a pulse after the request. (A snap would hold the camera's
        # lane of the control socket, so the pulses would wait behind it.)
        with FrameSubscriber(server.frames, "cam0") as frames:
            before = control.statistics("cam0").cameras[0].last_sequence
            ticket = control.trigger_ticket("cam0")
            assert ticket.sequence > before
            frame = None
            deadline = time.monotonic() + 60
            while frame is None and time.monotonic() < deadline:
                control.set_feature("cam0", "TriggerSoftware", "")
                got = frames.receive(timeout=0.3)
                if got is not None and got.header.sequence >= ticket.sequence:
                    frame = got
            assert frame is not None
            assert not frame.header.triggered  # the camera's own line, not a software trigger

        control.set_mode("cam0", "freerun", fps=10)
        assert control.hardware_trigger("cam0")["mode"] == "freerun"
        assert control.snap("cam0").image.size > 0  # free-run again: frames without pulses
