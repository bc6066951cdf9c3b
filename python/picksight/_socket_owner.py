"""The one way the clients own a ZeroMQ socket: closed by close() or at the
end of a `with` block, never lingering on unsent messages; and the one
receive loop of the subscribers (frames, results)."""

import time

import zmq


class SocketOwner:
    """Base of the clients that keep one ZeroMQ socket in self._socket."""

    _socket = None

    def close(self):
        if self._socket is not None:
            self._socket.close(linger=0)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


# What `_decode` returns for a message skipped and counted apart by the
# subclass (not malformed: a sealed frame under a key not given, say).
SKIPPED = object()


class TopicSubscriber(SocketOwner):
    """Base of the subscribers of one topic (all topics with topic="") on
    the SUB socket in self._socket: subclasses decode a message's parts
    (`_decode`, None for a malformed one, SKIPPED for one they counted
    apart) and count what they receive (`_count`)."""

    def __init__(self, endpoint, topic, queue_parts, context=None, curve=None):
        """Connects a SUB socket to `endpoint` for `topic`; `queue_parts`:
        the high-water mark, which counts message parts. `curve`: a
        picksight.CurveKeys for a server with CURVE."""
        self._context = context or zmq.Context.instance()
        self._socket = self._context.socket(zmq.SUB)
        if curve is not None:
            curve.apply(self._socket)
        self._socket.setsockopt(zmq.RCVHWM, queue_parts)
        self._socket.setsockopt(zmq.LINGER, 0)
        self._socket.setsockopt(zmq.SUBSCRIBE, topic.encode())
        self._socket.connect(endpoint)
        self._topic = topic
        self._last = {}
        self.received = 0
        self.lost = 0
        self.malformed = 0

    def _count_sequence(self, key, number):
        """Counts one message and the gap before it in `key`'s numbering (a
        number going back, a restarted sender, starts afresh)."""
        self.received += 1
        last = self._last.get(key)
        if last is not None and number > last + 1:
            self.lost += number - last - 1
        self._last[key] = number

    def receive(self, timeout=None):
        """The next message decoded, or None when none came within `timeout`
        seconds (None: wait for ever)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        once = True
        while True:
            wait_ms = None
            if deadline is not None:
                wait_ms = max(0, int((deadline - time.monotonic()) * 1000))
                # Past the deadline after a message that gave nothing: a
                # stream of skipped messages must not keep the poll from
                # ever timing out.
                if not once and wait_ms == 0:
                    return None
            once = False
            if not self._socket.poll(wait_ms, zmq.POLLIN):
                return None
            parts = self._socket.recv_multipart(copy=False)
            # Subscriptions match prefixes: "cam1" also receives "cam10".
            if self._topic and parts[0].bytes != self._topic.encode():
                continue
            item = self._decode(parts)
            if item is SKIPPED:
                continue
            if item is None:
                self.malformed += 1
                continue
            self._count(item)
            return item

    def __iter__(self):
        """Messages for ever (a loop over the subscriber)."""
        while True:
            item = self.receive()
            if item is not None:
                yield item

    def _decode(self, parts):
        raise NotImplementedError

    def _count(self, item):
        raise NotImplementedError
