"""The vision app's results stream: one VisionResult (proto/results.proto)
per vision request (LOCATE, LEARN, BLOBS, STORE, CALCAM), published after
the robot's reply on the endpoint picksight-vision prints as
`results <endpoint>` (option --results-bind).

A message is two ZeroMQ frames: the topic (the vision app's name) and the
serialized VisionResult. Coordinates are sensor pixels.
"""

from picksight import results_pb2 as rpb
from picksight._socket_owner import TopicSubscriber


class ResultsSubscriber(TopicSubscriber):
    """Subscribes to the results of one vision app (all apps with app="").

    `queue_results` bounds what ZeroMQ keeps for a slow reader: beyond it
    results are dropped (the vision app is never slowed); `lost` counts the
    gaps in each app's request_id, `malformed` the messages skipped. One
    thread uses a subscriber at a time."""

    def __init__(self, endpoint, app="", queue_results=16, context=None):
        # The high-water mark counts message parts; a result is two.
        super().__init__(endpoint, app, queue_results * 2, context)

    @staticmethod
    def _decode(parts):
        if len(parts) != 2:
            return None
        result = rpb.VisionResult()
        try:
            result.ParseFromString(parts[1].bytes)
        except Exception:  # a DecodeError, whatever the protobuf backend calls it
            return None
        return result

    def _count(self, result):
        self._count_sequence(result.app, result.request_id)
