"""FrameSubscriber: frames from a real video server as numpy arrays with
their header, and the gap and malformed-message counters on a PUB socket
the test drives itself."""

import numpy as np
import pytest
import zmq

from picksight import CameraControl, FrameSubscriber, decode_frame
from picksight import picksight_pb2 as pb


def first_frame(subscriber, control, camera="cam0"):
    """Triggers until the subscription has reached the server; the frame."""
    for _ in range(50):
        control.trigger(camera)
        frame = subscriber.receive(timeout=0.2)
        if frame is not None:
            return frame
    pytest.fail("no frame reached the subscriber")


def test_frames_arrive_as_numpy_images_with_their_header(synthetic_cell):
    server, _ = synthetic_cell
    with FrameSubscriber(server.frames, "cam0") as sub, CameraControl(server.control) as control:
        frame = first_frame(sub, control)
        assert frame.camera == "cam0"
        assert frame.image.shape == (480, 640)
        assert frame.image.dtype == np.uint8
        assert frame.header.width == 640 and frame.header.height == 480
        assert frame.header.pixel_format == pb.MONO8
        assert frame.header.triggered
        assert len(frame.header.truth) == 4
        # The synthetic parts are dark on a light background.
        assert frame.image.min() < 100 < frame.image.max()
        assert frame.to_sensor(0, 0) == (0.0, 0.0)

        # Colour, cropped and halved: the header says how to map back.
        control.set_format("cam0", "bgr8")
        control.set_roi("cam0", 100, 50, 400, 300)
        control.set_size("cam0", scale=0.5)
        for _ in range(50):
            sequence, _ = control.trigger("cam0")
            frame = sub.receive(timeout=2.0)
            if frame is not None and frame.sequence >= sequence and frame.image.ndim == 3:
                break
        assert frame.image.shape == (150, 200, 3)
        assert (frame.header.roi_x, frame.header.roi_y) == (100, 50)
        assert frame.to_sensor(0, 0) == pytest.approx((100.5, 50.5))


def test_sequence_gaps_and_malformed_messages_are_counted():
    context = zmq.Context.instance()
    pub = context.socket(zmq.PUB)
    pub.setsockopt(zmq.LINGER, 0)
    port = pub.bind_to_random_port("tcp://127.0.0.1")
    endpoint = f"tcp://127.0.0.1:{port}"

    def header(sequence, camera="cam1"):
        h = pb.FrameHeader(camera=camera, sequence=sequence, width=4, height=2, stride=6,
                           pixel_format=pb.MONO8)
        return h.SerializeToString()

    pixels = bytes(range(12))
    with FrameSubscriber(endpoint, "cam1", queue_frames=100) as sub:
        # Wait until the subscription reached the publisher.
        for _ in range(100):
            pub.send_multipart([b"cam1", header(1), pixels])
            if sub.receive(timeout=0.05) is not None:
                break
        else:
            pytest.fail("the subscription never reached the publisher")
        sub.received = sub.lost = 0
        sub._last.clear()
        sent = [
            [b"cam1", header(10), pixels],
            [b"cam10", header(11, "cam10"), pixels],  # another camera: not ours
            [b"cam1", b"\xff\xfe not a header", pixels],
            [b"cam1", header(11), pixels[:5]],  # fewer bytes than the rows need
            [b"cam1", header(12)],  # a part missing
            [b"cam1", header(14), pixels],  # 11..13 lost
            [b"cam1", header(3), pixels],  # a restarted server: counts afresh
            [b"cam1", header(4), pixels],
        ]
        for message in sent:
            pub.send_multipart(message)
        frames = [sub.receive(timeout=5.0) for _ in range(4)]
        assert [f.sequence for f in frames] == [10, 14, 3, 4]
        assert sub.received == 4
        assert sub.lost == 3
        assert sub.malformed == 3
        # Stride 6, width 4: the padding is not part of the image.
        assert frames[0].image.tolist() == [[0, 1, 2, 3], [6, 7, 8, 9]]
    pub.close()


def test_decode_frame_refuses_inconsistent_headers():
    pixels = bytes(100)
    ok = pb.FrameHeader(width=4, height=2, stride=12, pixel_format=pb.BGR8)
    assert decode_frame(ok, pixels).image.shape == (2, 4, 3)
    for bad in (
        pb.FrameHeader(width=4, height=2, stride=4, pixel_format=pb.BGR8),  # stride < row
        pb.FrameHeader(width=4, height=2, stride=4),  # no pixel format
        pb.FrameHeader(width=0, height=2, stride=4, pixel_format=pb.MONO8),
        pb.FrameHeader(width=50, height=50, stride=50, pixel_format=pb.MONO8),  # too few bytes
    ):
        assert decode_frame(bad, pixels) is None
