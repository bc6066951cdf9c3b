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
from picksight._socket_owner import SKIPPED, TopicSubscriber

# A sealed frame's part 2 beyond the header it seals: "PSF1", the key id,
# the nonce and the tag.
_SEALED_OVERHEAD = 4 + 8 + 12 + 16

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

    def __init__(self, endpoint, camera="", queue_frames=4, context=None, curve=None,
                 control=None):
        """`curve`: a picksight.CurveKeys for a video server with CURVE. Its
        frames come sealed, once each for every subscriber, on a plain
        socket; their key is asked at the server's `control` endpoint
        (required then) with those keys. A plain frame, one that does not
        open, or one sent again (its sequence not past the last) is counted
        in `malformed`; sealed frames under a key the server did not give
        (a refused client gets none) in `unopened`."""
        if curve is not None and not control:
            raise ValueError("a CURVE frame subscriber needs the video server's control "
                             "endpoint (the frames' key)")
        # The high-water mark counts message parts; a frame is three. The
        # frames' socket itself is plain.
        super().__init__(endpoint, camera, queue_frames * 3, context, None)
        self._keys = curve
        self._control = control
        self._key = None  # (key id, key)
        self._key_asked = None
        self.unopened = 0
        if curve is not None:
            # Asked now, while the subscription reaches the server: asked at
            # the first frame, the frames that came meanwhile could overflow
            # the queue.
            self._ask_key()

    def _decode(self, parts):
        if len(parts) != 3:
            return None
        header_bytes, pixels = parts[1].bytes, parts[2].buffer
        if self._keys is not None:
            opened = self._open(parts)
            if opened is None or opened is SKIPPED:
                return opened
            header_bytes, pixels = opened
        header = pb.FrameHeader()
        try:
            header.ParseFromString(header_bytes)
        except Exception:  # a DecodeError, whatever the protobuf backend calls it
            return None
        frame = decode_frame(header, pixels)
        if frame is not None and self._keys is not None:
            # Under one key a sealed frame's sequence only grows: one that
            # does not is a recorded frame sent again.
            last = self._last.get(header.camera)
            if last is not None and header.sequence <= last:
                return None
        return frame

    def _open(self, parts):
        """The header bytes and pixels of a sealed frame (picksight/transport/
        frame_seal.hpp); None when it does not open, SKIPPED (counted in
        `unopened`) when it is under a key the server did not give."""
        from nacl.bindings import crypto_aead_chacha20poly1305_ietf_decrypt as decrypt
        from nacl.exceptions import CryptoError

        envelope = parts[1].bytes
        if len(envelope) < _SEALED_OVERHEAD or envelope[:4] != b"PSF1":
            return None  # a plain frame: not taken from a server that should seal
        key_id = int.from_bytes(envelope[4:12], "little")
        if self._key is None or self._key[0] != key_id:
            self._ask_key()
            if self._key is None or self._key[0] != key_id:
                self.unopened += 1
                return SKIPPED
        # ChaCha20-Poly1305 (RFC 8439), bound to the topic and the clear
        # prefix; the pixels under the nonce plus one (little-endian).
        nonce = envelope[12:24]
        ad = parts[0].bytes + envelope[:24]
        pixel_nonce = ((int.from_bytes(nonce, "little") + 1) % (1 << 96)).to_bytes(12, "little")
        try:
            header = decrypt(envelope[24:], ad, nonce, self._key[1])
            pixels = decrypt(parts[2].bytes, ad, pixel_nonce, self._key[1])
        except CryptoError:
            return None
        return header, pixels

    def _ask_key(self):
        # At most once a second: frames under a key the server does not give
        # must not flood its control socket, nor stall the subscriber.
        now = time.monotonic()
        if self._key_asked is not None and now - self._key_asked < 1.0:
            return
        self._key_asked = now
        from picksight.control import CameraControl, ControlError

        request = pb.ControlRequest()
        request.frame_key.SetInParent()
        try:
            with CameraControl(self._control, context=self._context, curve=self._keys) as c:
                reply = c.call(request)
        except ControlError:
            return
        if len(reply.frame_key.key) == 32:
            if self._key is None or self._key[0] != reply.frame_key.key_id:
                self._last.clear()  # a new run of the server
            self._key = (reply.frame_key.key_id, reply.frame_key.key)

    def _count(self, frame):
        frame.received_ns = time.monotonic_ns()
        self._count_sequence(frame.header.camera, frame.header.sequence)
