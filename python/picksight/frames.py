"""Frames published by picksight-video-server, received as numpy arrays.

A frame on the wire is a three-part ZeroMQ message: the topic (the camera's
name), a serialized FrameHeader (proto/picksight.proto), and the pixel rows,
`stride` bytes each. Images are views on the received bytes (no copy) and
read-only.
"""

import time
from dataclasses import dataclass

import numpy as np

from picksight import picksight_pb2 as pb
from picksight._socket_owner import TopicSubscriber

# Bytes per pixel and channels of each wire pixel format.
_LAYOUT = {pb.MONO8: (1, None), pb.BGR8: (3, 3)}


@dataclass
class Frame:
    """One camera frame: `image` (height x width uint8, or height x width x 3
    in BGR order) and `header`, the FrameHeader as sent (camera, sequence,
    timestamps, ROI offset and scale to map pixels back to the sensor, the
    synthetic ground truth). `received_ns` is time.monotonic_ns() at receipt."""

    image: np.ndarray
    header: "pb.FrameHeader"
    received_ns: int = 0

    @property
    def camera(self):
        return self.header.camera

    @property
    def sequence(self):
        return self.header.sequence

    def to_sensor(self, u, v):
        """Sensor pixel of frame pixel (u, v) (pixel centres at integers)."""
        h = self.header
        sx = h.scale_x if h.scale_x > 0 else 1.0
        sy = h.scale_y if h.scale_y > 0 else 1.0
        return h.roi_x + (u + 0.5) / sx - 0.5, h.roi_y + (v + 0.5) / sy - 0.5


def decode_frame(header, pixels):
    """The Frame a FrameHeader and its pixel bytes describe, or None when they
    do not describe a consistent image (unknown format, zero size, stride
    shorter than a row, fewer bytes than the rows need)."""
    layout = _LAYOUT.get(header.pixel_format)
    if layout is None or header.width == 0 or header.height == 0:
        return None
    bpp, channels = layout
    if header.stride < header.width * bpp:
        return None
    data = memoryview(pixels)
    if header.stride * header.height > data.nbytes:
        return None
    rows = np.frombuffer(data, dtype=np.uint8, count=header.stride * header.height)
    rows = rows.reshape(header.height, header.stride)[:, : header.width * bpp]
    image = rows if channels is None else rows.reshape(header.height, header.width, channels)
    return Frame(image=image, header=header)


class FrameSubscriber(TopicSubscriber):
    """Subscribes to the frames of one camera (all cameras with camera="").

    `queue_frames` bounds what ZeroMQ keeps for a slow reader: beyond it the
    oldest frames are dropped (and counted in `lost`), the server is never
    slowed. Counters: `received`, `lost` (gaps in each camera's sequence
    numbers; a sequence going back, a restarted server, starts afresh) and
    `malformed` (messages skipped). One thread uses a subscriber at a time,
    like the ZeroMQ socket inside it."""

    def __init__(self, endpoint, camera="", queue_frames=4, context=None, curve=None):
        """`curve`: a picksight.CurveKeys for a video server with CURVE."""
        # The high-water mark counts message parts; a frame is three.
        super().__init__(endpoint, camera, queue_frames * 3, context, curve)

    @staticmethod
    def _decode(parts):
        if len(parts) != 3:
            return None
        header = pb.FrameHeader()
        try:
            header.ParseFromString(parts[1].bytes)
        except Exception:  # a DecodeError, whatever the protobuf backend calls it
            return None
        return decode_frame(header, parts[2].buffer)

    def _count(self, frame):
        frame.received_ns = time.monotonic_ns()
        self._count_sequence(frame.header.camera, frame.header.sequence)
