"""PickSight clients: camera frames as numpy arrays, the robot protocol, the
video server's camera control and the vision app's results stream, over
Debian's python3-zmq, python3-protobuf and python3-numpy.

    from picksight import FrameSubscriber, RobotClient, CameraControl, ResultsSubscriber
"""

from picksight.frames import Frame, FrameSubscriber, decode_frame
from picksight.robot import RobotClient, RobotError
from picksight.control import CameraControl, ControlError, ControlTimeout
from picksight.curve import CurveKeys
from picksight.results import ResultsSubscriber

__all__ = [
    "Frame",
    "FrameSubscriber",
    "decode_frame",
    "RobotClient",
    "RobotError",
    "CameraControl",
    "ControlError",
    "ControlTimeout",
    "CurveKeys",
    "ResultsSubscriber",
]
