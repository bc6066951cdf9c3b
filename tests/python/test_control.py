"""CameraControl against a real video server: every request of the control
socket, snapshots as numpy images, refusals raised with their wire code."""

import time

import pytest
import zmq

from picksight import CameraControl, ControlError, ControlTimeout
from picksight import picksight_pb2 as pb


def test_cameras_and_settings(cell_factory):
    server, _ = cell_factory("--source", "cam0=synthetic:width=640,height=480,parts=4,seed=3",
                             "--source", "cam1=synthetic:width=320,height=240,parts=1",
                             "--mode", "trigger", vision=False)
    with CameraControl(server.control) as control:
        cameras = control.list_cameras()
        assert [c.name for c in cameras] == ["cam0", "cam1"]
        assert cameras[0].mode == pb.TRIGGER
        assert control.snap("cam0").image.shape == (480, 640)
        d = control.describe("cam0")  # the camera is open once it gave a frame
        assert (d.sensor_width, d.sensor_height) == (640, 480)

        frame = control.snap("cam1")
        assert frame.image.shape == (240, 320)
        assert frame.camera == "cam1"

        control.set_roi("cam0", 10, 20, 300, 200)
        control.set_format("cam0", "bgr8")
        frame = control.snap("cam0")
        assert frame.image.shape == (200, 300, 3)
        assert (frame.header.roi_x, frame.header.roi_y) == (10, 20)
        control.set_size("cam0", width=150, height=100)
        assert control.snap("cam0").image.shape == (100, 150, 3)
        control.set_size("cam0")
        control.set_roi("cam0")
        control.set_format("cam0", "mono8")
        assert control.snap("cam0").image.shape == (480, 640)

        sequence, triggered = control.trigger("cam0")
        assert triggered
        control.set_mode("cam0", "freerun", fps=20)
        assert control.describe("cam0").summary.mode == pb.FREERUN
        _, triggered = control.trigger("cam0")
        assert not triggered

        stats = control.statistics()
        assert {c.camera for c in stats.cameras} == {"cam0", "cam1"}
        assert control.statistics("cam0").cameras[0].frames_acquired >= 1

        control.close_stream("cam1")
        # The camera thread closes the device after the reply: poll for it.
        deadline = time.monotonic() + 10
        while control.list_cameras()[1].state != "closed" and time.monotonic() < deadline:
            time.sleep(0.02)
        assert control.list_cameras()[1].state == "closed"
        control.open_stream("cam1")
        assert control.snap("cam1").image.shape == (240, 320)

        features = control.list_features("cam0")
        assert isinstance(features, list)
        with pytest.raises(ControlError) as e:
            control.get_feature("cam0", "NoSuchFeature")
        assert e.value.code in (pb.Error.UNKNOWN_FEATURE, pb.Error.NOT_SUPPORTED)


def test_refusals_carry_their_wire_code(cell_factory):
    server, _ = cell_factory("--source", "cam0=synthetic:width=640,height=480,parts=1",
                             "--mode", "trigger", vision=False)
    with CameraControl(server.control) as control:
        with pytest.raises(ControlError) as e:
            control.trigger("nosuch")
        assert e.value.code == pb.Error.UNKNOWN_CAMERA
        assert e.value.name == "UNKNOWN_CAMERA"
        with pytest.raises(ControlError) as e:
            control.set_mode("cam0", "freerun", fps=5000)  # beyond 1000 fps
        assert e.value.code == pb.Error.OUT_OF_RANGE
        assert control.list_cameras()[0].mode == pb.TRIGGER  # left as it was
        with pytest.raises(ControlError) as e:
            control.set_size("cam0", scale=100)
        assert e.value.code == pb.Error.OUT_OF_RANGE


def test_no_reply_is_a_timeout_and_the_client_recovers(cell_factory):
    # A ROUTER that never answers, then the real server at the same client.
    context = zmq.Context.instance()
    silent = context.socket(zmq.ROUTER)
    silent.setsockopt(zmq.LINGER, 0)
    port = silent.bind_to_random_port("tcp://127.0.0.1")
    control = CameraControl(f"tcp://127.0.0.1:{port}", timeout=0.2)
    with pytest.raises(ControlTimeout) as e:
        control.list_cameras()
    assert e.value.code is None
    silent.close()
    control.close()


def test_hardware_trigger_mode_is_refused_by_a_camera_without_an_input(cell_factory):
    server, _ = cell_factory("--source", "cam0=synthetic:width=320,height=240,parts=1",
                             "--mode", "trigger", vision=False)
    with CameraControl(server.control) as control:
        with pytest.raises(ControlError) as e:
            control.set_hardware_trigger("cam0", line="Line1", timeout=2.0)
        assert e.value.code == pb.Error.NOT_SUPPORTED
        assert "hardware trigger" in e.value.text
        with pytest.raises(ValueError):
            control.set_mode("cam0", "hardware", activation="Sideways")
        assert control.hardware_trigger("cam0")["mode"] == "trigger"  # left as it was
        ticket = control.trigger_ticket("cam0")
        assert ticket.triggered and ticket.mode == pb.TRIGGER
