"""The one way the clients own a ZeroMQ socket: closed by close() or at the
end of a `with` block, never lingering on unsent messages."""


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
