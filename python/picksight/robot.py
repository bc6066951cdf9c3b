"""The robot protocol (docs/PROTOCOL.md) as Python calls with parsed replies.

Every command of the protocol is a method; an `ERROR <code> <text>` reply is
raised as RobotError carrying the code, and a lost connection or a reply
that does not come in time as the socket's own OSError (ConnectionError,
TimeoutError).
"""

import socket
from collections import namedtuple

Pose = namedtuple("Pose", "x y rz")
TypedPose = namedtuple("TypedPose", "type x y rz")
Finger = namedtuple("Finger", "x y width height")
Model = namedtuple("Model", "type name area holes symmetry mirror_symmetric")
FrameInfo = namedtuple("FrameInfo", "camera sequence host_timestamp_ns width height triggered")
CalibrationPoint = namedtuple("CalibrationPoint", "id xv yv xr yr")
Transform = namedtuple("Transform", "dx dy rz rms")
Residual = namedtuple("Residual", "id dx dy distance")
Exposure = namedtuple("Exposure", "feature value")
Roi = namedtuple("Roi", "x y width height")
# The vision settings (VISION): `values` maps each key of the reply, in its
# order, to its value (int or float for numbers, str for words: "dark",
# "adaptive", "auto"), so keys a later vision app adds are kept too;
# `reteach` the models a change left taught under other settings, as the
# reply names them ("1 (coin) taught as dark on its surface"); `notes` the
# reply's other remarks (a damaged settings file).
VisionSettings = namedtuple("VisionSettings", "values reteach notes")
# A model's tolerances (TOLERANCE): `values` maps each key of the reply, in
# its order, to its value (float; bool for mirror_symmetric), so keys a later
# vision app adds are kept too.
Tolerances = namedtuple("Tolerances", "type name values")
# mode "FREE" (fps), "SOFTWARE" or "HARDWARE" (line, timeout in s); None where
# the mode has no such setting.
CameraMode = namedtuple("CameraMode", "mode fps line timeout")
# UNDO: the type, whether a model was restored (False: the undone change had
# created it), the changes still undoable, and the request undone.
Undone = namedtuple("Undone", "type restored left change")
# TRYLEARN: the model LEARN would store, the parts of its type and all parts
# LOCATE ALL then finds on that frame, and LEARN's warnings.
TriedModel = namedtuple("TriedModel", "model found parts warnings")
# LEARNVIEW: the model's type and name, the images it is taught from now,
# where its origin lies from the centroid LEARN read (sensor px, the teach
# image's axes), the views' spread about it, and this view's reading.
View = namedtuple("View", "type name views dx dy spread reading")
# JOB SAVE / LOAD: the job's name, its models, whether it holds a
# calibration and camera settings, the job file's size (None after a load)
# and the notes after ';' (e.g. why the camera settings were not kept).
Job = namedtuple("Job", "name models calibrated camera bytes notes")
Blob = namedtuple(
    "Blob",
    "x y angle area perimeter roundness holes eccentricity bx by bw bh "
    "h1 h2 h3 h4 h5 h6 h7",
)

# A reply longer than this is not the vision app's: the connection is dropped.
MAX_REPLY_BYTES = 16 * 1024 * 1024
# Requests longer than this are refused by the server (ERROR 12).
MAX_REQUEST_BYTES = 4096


class RobotError(Exception):
    """An `ERROR <code> <text>` reply: `code` is the protocol's error code
    (docs/PROTOCOL.md, e.g. 32 no model for that type), `text` its message."""

    def __init__(self, code, text, request=""):
        super().__init__(f"ERROR {code} {text}" + (f" (request: {request})" if request else ""))
        self.code = code
        self.text = text
        self.request = request


def _number(value):
    """A number as the protocol wants it: '.' decimal point, no exponent."""
    if isinstance(value, int):
        return str(value)
    text = f"{float(value):.6f}".rstrip("0").rstrip(".")
    return text if text not in ("", "-0") else "0"


def _groups(words, size, kind, convert):
    """`OK <n>` followed by n groups of `size` words, as `kind` tuples."""
    n = int(words[0])
    rest = words[1:]
    if len(rest) != n * size:
        raise ValueError(f"expected {n} groups of {size} fields, got {len(rest)} fields")
    return [kind(*convert(rest[i : i + size])) for i in range(0, len(rest), size)]


def _floats(fields):
    return [float(f) for f in fields]


def _status_value(key, text):
    if text == "none":
        return None
    if key == "scale":
        return tuple(float(v) for v in text.split("x"))
    if key == "transform":
        return tuple(float(v) for v in text.split(","))
    for convert in (int, float):
        try:
            return convert(text)
        except ValueError:
            pass
    return text


def _job_name(name):
    """A job name as the protocol takes it (one word; the vision app checks
    the rest and answers RobotError 54)."""
    name = str(name)
    if not name or any(c.isspace() for c in name):
        raise ValueError(f"a job name is one word, got {name!r}")
    return name


def _job(words, saved):
    """A JOB SAVE or LOAD reply: name models calibrated camera [bytes] [; ...]."""
    fields, notes = [], []
    if ";" in words:
        cut = words.index(";")
        fields, rest = words[:cut], " ".join(words[cut + 1:])
        notes = [n.strip() for n in rest.split(" ; ") if n.strip()]
    else:
        fields = words
    return Job(fields[0], int(fields[1]), fields[2] == "1", fields[3] == "1",
               int(fields[4]) if saved else None, notes)


def _vision_settings(words):
    """VISION's reply words: `key=value`..., then ` ; `-separated remarks."""
    head, *remarks = " ".join(words).split(" ; ")
    values = {}
    for word in head.split():
        key, sep, text = word.partition("=")
        if not sep:
            raise ValueError(f"not a key=value field in the VISION reply: {word!r}")
        try:
            values[key] = int(text)
        except ValueError:
            try:
                values[key] = float(text)
            except ValueError:
                values[key] = text
    reteach = [r[len("re-teach: "):] for r in remarks if r.startswith("re-teach: ")]
    notes = [r for r in remarks if not r.startswith("re-teach: ")]
    return VisionSettings(values, reteach, notes)


class RobotClient:
    """A connection to a vision app's robot port. One request at a time (the
    protocol is synchronous per connection); use one client per thread.
    After a connection error or a timeout the client is closed: make a new
    one."""

    def __init__(self, host="127.0.0.1", port=5600, timeout=10.0):
        self.host = host
        self.port = port
        self._socket = socket.create_connection((host, port), timeout=timeout)
        self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._reader = self._socket.makefile("rb")

    def close(self):
        self._reader.close()
        self._socket.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    # ------------------------------------------------------------ raw lines

    def request(self, line):
        """Sends one request line; returns the reply's words after `OK`.
        Raises RobotError for `ERROR` replies."""
        if "\n" in line or "\r" in line:
            raise ValueError("a request is one line")
        data = line.encode() + b"\n"
        try:
            self._socket.sendall(data)
            reply = self._reader.readline(MAX_REPLY_BYTES)
        except OSError:
            # A late reply would be read as the next request's: this
            # connection is done (TimeoutError included).
            self.close()
            raise
        if not reply:
            raise ConnectionError(f"{self.host}:{self.port} closed the connection")
        if not reply.endswith(b"\n"):
            self.close()
            raise ConnectionError(f"reply longer than {MAX_REPLY_BYTES} bytes")
        words = reply.decode(errors="replace").rstrip("\r\n").split(" ")
        if words[0] == "OK":
            return [w for w in words[1:] if w]
        if words[0] == "ERROR" and len(words) >= 2 and words[1].isdigit():
            raise RobotError(int(words[1]), " ".join(words[2:]), line)
        raise ValueError(f"not a protocol reply: {reply!r}")

    # ----------------------------------------------------------------- core

    def ping(self):
        self.request("PING")

    def version(self):
        return " ".join(self.request("VERSION"))

    def help(self):
        """Every command's usage, separated by " | " (as sent: the usages of
        GRASP, GRIPPER and ROI hold " | " themselves, so no split is exact)."""
        return " ".join(self.request("HELP"))

    def status(self):
        """STATUS as a dict by key: numbers as int or float, `scale` as
        (mm_x, mm_y), `transform` as (dx, dy, rz), None for `none`."""
        out = {}
        for word in self.request("STATUS"):
            key, _, value = word.partition("=")
            out[key] = _status_value(key, value)
        return out

    def frame(self):
        """The frame the last vision request worked on."""
        w = self.request("FRAME")
        return FrameInfo(w[0], int(w[1]), int(w[2]), int(w[3]), int(w[4]), w[5] == "1")

    # ------------------------------------------------------ locating, picking

    def locate(self, part_type):
        """The grasp poses of the parts of `part_type`, best first."""
        return _groups(self.request(f"LOCATE {int(part_type)}"), 3, Pose, _floats)

    def locate_all(self):
        """The grasp poses of every trained type in one pass, each with its
        type (-1: a region, when no model exists), best first."""

        def convert(f):
            return [int(f[0])] + _floats(f[1:])

        return _groups(self.request("LOCATE ALL"), 4, TypedPose, convert)

    def why(self):
        """(n, text): why the last LOCATE on this connection left regions
        out, one "; "-separated sentence per region."""
        words = self.request("WHY")
        return int(words[0]), " ".join(words[1:])

    def grasp_add(self, part_type, x, y, rz):
        """Adds a grasp style; returns the type's number of styles."""
        return int(self.request(f"GRASP {int(part_type)} ADD {_number(x)} {_number(y)} {_number(rz)}")[0])

    def grasp_clear(self, part_type):
        self.request(f"GRASP {int(part_type)} CLEAR")

    def grasp_list(self, part_type):
        return _groups(self.request(f"GRASP {int(part_type)} LIST"), 3, Pose, _floats)

    def gripper_finger(self, part_type, x, y, width, height):
        """Adds a finger rectangle; returns the type's number of fingers."""
        args = " ".join(_number(v) for v in (x, y, width, height))
        return int(self.request(f"GRIPPER {int(part_type)} FINGER {args}")[0])

    def gripper_clear(self, part_type):
        self.request(f"GRIPPER {int(part_type)} CLEAR")

    def gripper_list(self, part_type):
        return _groups(self.request(f"GRIPPER {int(part_type)} LIST"), 4, Finger, _floats)

    # ------------------------------------------------------ teaching, blobs

    @staticmethod
    def _learn_line(word, part_type, name, at):
        line = f"{word} {int(part_type)}" + (f" {name}" if name else "")
        if at is not None:
            line += " AT " + " ".join(str(int(v)) for v in at)
        return line

    def learn(self, part_type, name=None, at=None):
        """Trains `part_type` from the single part in a fresh frame (inside
        `at` = (x, y, w, h) sensor pixels when given)."""
        w = self.request(self._learn_line("LEARN", part_type, name, at))
        return Model(int(w[0]), w[1], float(w[2]), int(w[3]), float(w[4]), w[5] == "1")

    def try_learn(self, part_type, name=None, at=None):
        """What LEARN would store and LOCATE ALL would then find on the same
        frame, storing nothing (TRYLEARN). Returns a TriedModel."""
        line = self._learn_line("TRYLEARN", part_type, name, at)
        if "\n" in line or "\r" in line:
            raise ValueError("a request is one line")
        w = self.request(line)
        text = " ".join(w)
        warnings = [p[len("warning: "):] for p in text.split(" ; ")[1:] if p.startswith("warning: ")]
        model = Model(int(w[0]), w[1], float(w[2]), int(w[3]), float(w[4]), w[5] == "1")
        return TriedModel(model, int(w[6]), int(w[7]), warnings)

    def learn_view(self, part_type, at=None):
        """Reads the taught part of `part_type` again where it lies now
        (alone, or inside `at` = (x, y, w, h) sensor pixels), moving the
        model's origin to the median of the views (LEARNVIEW). RobotError 39
        when the view cannot refine the model (a symmetric part, a part
        touching another, a reading far off). Returns a View."""
        line = f"LEARNVIEW {int(part_type)}"
        if at is not None:
            line += " AT " + " ".join(str(int(v)) for v in at)
        w = self.request(line)
        text = " ".join(w)
        reading = None
        marker = "this view read the centroid at "
        if marker in text:
            x, y = text.split(marker, 1)[1].split(";")[0].split()[:2]
            reading = (float(x), float(y))
        return View(int(w[0]), w[1], int(w[2]), float(w[3]), float(w[4]), float(w[5]), reading)

    def undo(self):
        """Takes back the last change to models (LEARN, FORGET, TOLERANCE,
        GRASP, GRIPPER): the model file as it was. RobotError 37 when there
        is nothing to undo, 38 when the history entry is damaged or no longer
        applies. Returns an Undone."""
        w = self.request("UNDO")
        text = " ".join(w)
        parts = text.split(" ; ")
        change = parts[1][len("undid: "):] if len(parts) > 1 and parts[1].startswith("undid: ") else ""
        return Undone(int(w[0]), w[1] == "restored", int(w[2]), change)

    def models(self):
        def convert(f):
            return int(f[0]), f[1], float(f[2]), int(f[3]), float(f[4]), None

        return _groups(self.request("MODELS"), 5, Model, convert)

    def tolerance(self, part_type, **changes):
        """Reads a model's tolerances (TOLERANCE <type>), or changes some and
        reads back the values in force: e.g. tolerance(1, area_tolerance=0.2,
        mirror_symmetric=True). The vision app checks every pair before any
        applies: an unknown key or a value out of its bounds is RobotError
        code 11 naming the key, and nothing changes. Returns a Tolerances."""
        line = f"TOLERANCE {int(part_type)}"
        for key, value in changes.items():
            if isinstance(value, bool):
                value = int(value)
            line += f" {key} {_number(value)}"
        words = self.request(line)
        values = {}
        for word in words[2:]:
            key, sep, text = word.partition("=")
            if not sep:
                raise ValueError(f"not a key=value field in the TOLERANCE reply: {word!r}")
            if key == "mirror_symmetric":
                values[key] = text == "1"
            else:
                try:
                    values[key] = float(text)
                except ValueError:
                    values[key] = text  # a later key that is not a number
        return Tolerances(int(words[0]), words[1], values)

    def vision_settings(self, **changes):
        """Reads the vision settings in force (VISION), or changes some and
        reads back the values in force: e.g. vision_settings(polarity="light",
        min_hole_area=150). Keys: polarity ("dark"/"light"), threshold
        ("adaptive"/"otsu"/"fixed"), level, window, min_area (a number or
        "auto"), min_hole_area. The vision app checks every pair before any
        applies: an unknown key or a value out of its bounds is RobotError
        code 11 naming the key, and nothing changes; a damaged settings file
        is code 48. Returns a VisionSettings."""
        line = "VISION"
        for key, value in changes.items():
            text = value if isinstance(value, str) else _number(value)
            if not text or any(c.isspace() for c in text):
                raise ValueError(f"{key}: one word, got {value!r}")
            line += f" {key} {text}"
        return _vision_settings(self.request(line))

    def vision_settings_reset(self):
        """VISION RESET: the settings in force written over a damaged
        settings file, which lifts the refusal of LOCATE and LEARN."""
        return _vision_settings(self.request("VISION RESET"))

    # ------------------------------------------------------------------ jobs

    def job_save(self, name):
        """JOB SAVE: the cell as it is now (models with their teach images
        and grasps, vision settings, calibration, camera settings) saved as
        job `name`. Returns a Job."""
        return _job(self.request(f"JOB SAVE {_job_name(name)}"), saved=True)

    def job_load(self, name):
        """JOB LOAD: job `name` in force, in one switch no LOCATE sees half
        of. RobotError 50 when there is no such job, 51 when its file is
        damaged (nothing changed). Returns a Job."""
        return _job(self.request(f"JOB LOAD {_job_name(name)}"), saved=False)

    def job_list(self):
        """The names of the stored jobs, sorted."""
        words = self.request("JOB LIST")
        return words[1:1 + int(words[0])]

    def job_current(self):
        """The job last saved or loaded; None before any."""
        name = self.request("JOB")[0]
        return None if name == "none" else name

    def job_delete(self, name):
        self.request(f"JOB DELETE {_job_name(name)}")

    def forget(self, part_type):
        self.request(f"FORGET {int(part_type)}")

    def blobs(self):
        """Blob features of every region of a fresh frame, largest first."""

        def convert(f):
            v = _floats(f)
            v[6] = int(v[6])
            return v

        return _groups(self.request("BLOBS"), 19, Blob, convert)

    # ---------------------------------------------------------- calibration

    def calcam(self, radius_mm):
        """Camera scale from a disc target: (mm per pixel x, y)."""
        w = self.request(f"CALCAM {_number(radius_mm)}")
        return float(w[0]), float(w[1])

    def store(self, x, y):
        """Stores a calibration point (robot x, y mm); returns its id."""
        return int(self.request(f"STORE {_number(x)} {_number(y)}")[0])

    def delete(self, point_id):
        self.request(f"DELETE {int(point_id)}")

    def list_points(self):
        def convert(f):
            return [int(f[0])] + _floats(f[1:])

        return _groups(self.request("LIST"), 5, CalibrationPoint, convert)

    def compute(self, method=None):
        """Fits the robot-camera transform (method BEST, LSQ or GEOMETRIC)."""
        w = self.request("COMPUTE" + (f" {method}" if method else ""))
        return Transform(*_floats(w))

    def residuals(self):
        def convert(f):
            return [int(f[0])] + _floats(f[1:])

        return _groups(self.request("RESIDUALS"), 4, Residual, convert)

    # ------------------------------------------------------ camera settings

    def exposure(self, value=None):
        """Reads, or sets and reads back, the camera's exposure."""
        w = self.request("EXPOSURE" + ("" if value is None else f" {_number(value)}"))
        return Exposure(w[0], float(w[1]))

    def roi(self, x=None, y=None, width=None, height=None):
        """Reads the camera's region, or crops it (all four given).

        Right after a start, before the camera has first opened, its size is
        not known: the read raises RobotError with code 20; ask again."""
        given = [v is not None for v in (x, y, width, height)]
        if any(given):
            if not all(given):
                raise ValueError("roi needs x, y, width and height, or none of them")
            self.request(f"ROI {int(x)} {int(y)} {int(width)} {int(height)}")
            return None
        return Roi(*(int(v) for v in self.request("ROI")))

    def camera_mode(self, mode=None, fps=None, line=None, timeout=None):
        """Reads, or sets and reads back, the camera's acquisition mode
        (CAMMODE): "free" (at `fps`, None: as it is), "software", or
        "hardware" (one frame per pulse on `line`, None: Line1; a request
        waits up to `timeout` seconds for it, None: 10 s, and fails with
        RobotError code 23 when none came). Returns a CameraMode."""
        if mode is None:
            words = self.request("CAMMODE")
        else:
            kind = str(mode).upper()
            request = f"CAMMODE {kind}"
            if kind == "FREE" and fps is not None:
                request += f" {_number(fps)}"
            elif kind == "HARDWARE":
                if timeout is not None and line is None:
                    line = "Line1"
                if line is not None:
                    request += f" {line}"
                if timeout is not None:
                    request += f" {int(round(timeout * 1000))}"
            words = self.request(request)
        if words[0] == "FREE":
            return CameraMode("FREE", float(words[1]), None, None)
        if words[0] == "HARDWARE":
            return CameraMode("HARDWARE", None, words[1], int(words[2]) / 1000.0)
        return CameraMode(words[0], None, None, None)

    def roi_full(self):
        self.request("ROI FULL")
