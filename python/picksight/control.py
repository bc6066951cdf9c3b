"""The video server's control socket: camera list, settings, features,
triggers, snapshots and statistics.

A request is one serialized ControlRequest (proto/picksight.proto) on a REQ
socket, the reply one ControlReply. A reply whose error code is not OK is
raised as ControlError; no reply in time as ControlTimeout, after which the
socket is replaced (a REQ socket that missed its reply cannot send again).
"""

import zmq

from picksight import picksight_pb2 as pb
from picksight._socket_owner import SocketOwner
from picksight.frames import decode_frame

_MODES = {"freerun": pb.FREERUN, "trigger": pb.TRIGGER, "hardware": pb.HARDWARE_TRIGGER}
_ACTIVATIONS = ("", "RisingEdge", "FallingEdge", "AnyEdge", "LevelHigh", "LevelLow")
_FORMATS = {"mono8": pb.MONO8, "bgr8": pb.BGR8}


class ControlError(Exception):
    """The server refused a request: `code` is the wire code
    (picksight_pb2.Error.Code, e.g. Error.UNKNOWN_CAMERA), `name` its name."""

    def __init__(self, code, text):
        self.code = code
        self.name = pb.Error.Code.Name(code) if code in pb.Error.Code.values() else str(code)
        self.text = text
        super().__init__(f"{self.name}: {text}")


class ControlTimeout(ControlError):
    """The server did not answer in time (code None)."""

    def __init__(self, text):
        Exception.__init__(self, text)
        self.code = None
        self.name = "NO_REPLY"
        self.text = text


class CameraControl(SocketOwner):
    """A client of picksight-video-server's control endpoint. Replies are the
    protobuf messages of proto/picksight.proto; `snap` returns a Frame. One
    thread uses a client at a time."""

    def __init__(self, endpoint, timeout=2.0, context=None, curve=None):
        """`curve`: a picksight.CurveKeys for a video server with CURVE."""
        self.endpoint = endpoint
        self.timeout = timeout
        self._curve = curve
        self._context = context or zmq.Context.instance()
        self._socket = None
        self._connect()

    def _connect(self):
        if self._socket is not None:
            self._socket.close(linger=0)
        self._socket = self._context.socket(zmq.REQ)
        self._socket.setsockopt(zmq.LINGER, 0)
        if self._curve is not None:
            self._curve.apply(self._socket)
        self._socket.connect(self.endpoint)

    def call(self, request, timeout=None):
        """Sends a ControlRequest; returns the ControlReply when its code is OK."""
        self._socket.send(request.SerializeToString())
        wait = self.timeout if timeout is None else timeout
        if not self._socket.poll(int(wait * 1000), zmq.POLLIN):
            self._connect()
            raise ControlTimeout(f"video server at {self.endpoint} did not answer within {wait} s")
        reply = pb.ControlReply()
        reply.ParseFromString(self._socket.recv())
        if reply.HasField("error") and reply.error.code != pb.Error.OK:
            raise ControlError(reply.error.code, reply.error.text)
        return reply

    # -------------------------------------------------------------- cameras

    def list_cameras(self):
        """The cameras (CameraSummary: name, source, state, mode)."""
        r = pb.ControlRequest()
        r.list_cameras.SetInParent()
        return list(self.call(r).list_cameras.cameras)

    def describe(self, camera):
        r = pb.ControlRequest()
        r.describe_camera.camera = camera
        return self.call(r).describe_camera

    def set_roi(self, camera, x=0, y=0, width=0, height=0):
        """Crops the camera to a sensor region (width = height = 0: the full sensor)."""
        r = pb.ControlRequest()
        r.set_roi.camera = camera
        r.set_roi.roi.x, r.set_roi.roi.y = x, y
        r.set_roi.roi.width, r.set_roi.roi.height = width, height
        self.call(r)

    def set_size(self, camera, width=0, height=0, scale=0.0):
        """Output size after the ROI: a target size, or a scale (all 0: the ROI's)."""
        r = pb.ControlRequest()
        r.set_size.camera = camera
        r.set_size.width, r.set_size.height, r.set_size.scale = width, height, scale
        self.call(r)

    def set_mode(self, camera, mode, fps=0.0, line="", activation="", trigger_timeout=0.0):
        """mode "freerun", "trigger" (software) or "hardware" (one frame per
        pulse on the camera's input `line`, e.g. "Line1"; `activation` one of
        RisingEdge, FallingEdge, AnyEdge, LevelHigh, LevelLow, "" = as the
        camera is set; `trigger_timeout` in s: how long a snap or a robot's
        LOCATE waits for a pulse, 0 = the server's default, 10 s). fps 0
        leaves the rate unchanged. A camera without a trigger input (V4L2,
        synthetic, files) refuses "hardware" with NOT_SUPPORTED."""
        if mode not in _MODES:
            raise ValueError(f"mode must be one of {sorted(_MODES)}, got {mode!r}")
        if activation not in _ACTIVATIONS:
            raise ValueError(f"activation must be one of {_ACTIVATIONS[1:]} or empty")
        r = pb.ControlRequest()
        r.set_mode.camera = camera
        r.set_mode.mode = _MODES[mode]
        r.set_mode.fps = fps
        if mode == "hardware":
            r.set_mode.trigger_line = line
            r.set_mode.trigger_activation = activation
            r.set_mode.trigger_timeout_ms = int(round(trigger_timeout * 1000))
        self.call(r)

    def set_hardware_trigger(self, camera, line="Line1", activation="", timeout=10.0):
        """Hardware-trigger mode on `line` (see set_mode)."""
        self.set_mode(camera, "hardware", line=line, activation=activation, trigger_timeout=timeout)

    def hardware_trigger(self, camera):
        """The camera's hardware trigger settings as a dict: mode ("freerun",
        "trigger" or "hardware"), line, activation, timeout (s); the line
        settings are kept in every mode."""
        d = self.describe(camera)
        names = {v: k for k, v in _MODES.items()}
        return {
            "mode": names.get(d.summary.mode, "freerun"),
            "line": d.trigger_line,
            "activation": d.trigger_activation,
            "timeout": d.trigger_timeout_ms / 1000.0,
        }

    def set_format(self, camera, pixel_format):
        """pixel_format "mono8" or "bgr8"."""
        r = pb.ControlRequest()
        r.set_format.camera = camera
        r.set_format.pixel_format = _FORMATS[pixel_format]
        self.call(r)

    def trigger(self, camera):
        """A software trigger; returns (sequence, triggered): waiting for that
        sequence number gives a frame taken after the request. In hardware
        mode nothing is triggered: the sequence is that of the next pulse's
        frame (trigger_ticket gives the line and the timeout too)."""
        r = pb.ControlRequest()
        r.trigger.camera = camera
        t = self.call(r).trigger
        return t.sequence, t.triggered

    def trigger_ticket(self, camera):
        """The whole TriggerReply: sequence, triggered, mode and, in hardware
        mode, trigger_line and trigger_timeout_ms."""
        r = pb.ControlRequest()
        r.trigger.camera = camera
        return self.call(r).trigger

    def statistics(self, camera=""):
        """StatisticsReply: per-camera counters and the subscriber count."""
        r = pb.ControlRequest()
        r.statistics.camera = camera
        return self.call(r).statistics

    def open_stream(self, camera):
        r = pb.ControlRequest()
        r.open_stream.camera = camera
        self.call(r)

    def close_stream(self, camera):
        r = pb.ControlRequest()
        r.close_stream.camera = camera
        self.call(r)

    def snap(self, camera, timeout=5.0):
        """The camera's next frame (triggered in trigger mode, the next
        pulse's in hardware mode) as a Frame. The server itself waits up to
        3 s for it, or the camera's trigger timeout in hardware mode: pass a
        `timeout` longer than that one."""
        r = pb.ControlRequest()
        r.snap.camera = camera
        s = self.call(r, timeout=max(timeout, self.timeout)).snap
        frame = decode_frame(s.header, s.pixels)
        if frame is None:
            raise ControlError(pb.Error.INTERNAL, "snap reply holds no consistent image")
        return frame

    # ------------------------------------------------------------- features

    def list_features(self, camera):
        r = pb.ControlRequest()
        r.list_features.camera = camera
        return list(self.call(r).list_features.features)

    def get_feature(self, camera, name):
        r = pb.ControlRequest()
        r.get_feature.camera, r.get_feature.name = camera, name
        return self.call(r).feature.feature

    def set_feature(self, camera, name, value):
        """Sets a feature (value as text); returns the Feature read back."""
        r = pb.ControlRequest()
        r.set_feature.camera, r.set_feature.name = camera, name
        r.set_feature.value = str(value)
        return self.call(r).feature.feature
