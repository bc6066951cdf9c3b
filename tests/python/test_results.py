"""ResultsSubscriber against a real cell: the VisionResult of a LOCATE, with
as many parts as the reply and the reply's poses."""

import time

from picksight import ResultsSubscriber, RobotClient


def _first_result(robot, results, line, timeout=10.0):
    """Sends `line` until a result comes back (a SUB socket joins a moment
    after it connects); the reply and the result of the last one sent."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        reply = robot.request(line)
        result = results.receive(timeout=0.5)
        if result is not None:
            # Results that were on their way belong to earlier requests.
            while True:
                newer = results.receive(timeout=0.2)
                if newer is None:
                    return reply, result
                result = newer
    raise TimeoutError("no result on the results stream")


def test_locate_result_matches_the_reply(synthetic_cell):
    _, vision = synthetic_cell
    assert vision.results.startswith("tcp://127.0.0.1:")
    with ResultsSubscriber(vision.results, app="cam0") as results, RobotClient(
        "127.0.0.1", vision.port
    ) as robot:
        _first_result(robot, results, "LOCATE 1")
        reply = robot.request("LOCATE 1")
        result = results.receive(timeout=10)
        assert result is not None
        assert result.app == "cam0" and result.request == "LOCATE"
        assert result.request_line == "LOCATE 1"
        assert result.reply == "OK " + " ".join(reply)
        assert result.client.startswith("robot 127.0.0.1:")
        n = int(reply[0])
        assert n == 4 and len(result.parts) == n and len(result.regions) == n
        assert result.camera == "cam0" and result.frame_width == 640
        for part, i in zip(result.parts, range(n)):
            assert part.offered
            assert abs(part.reply_pose.x - float(reply[1 + 3 * i])) < 1e-3
            assert abs(part.reply_pose.y - float(reply[2 + 3 * i])) < 1e-3
        assert all(len(r.outline.points) >= 3 for r in result.regions)
        assert results.lost == 0 and results.malformed == 0
