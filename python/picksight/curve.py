"""CURVE keys for the video server's sockets (docs/SECURITY.md): the files
picksight-keygen writes, read with pyzmq's own certificate reader, and the
socket options that make a ZeroMQ socket a CURVE client."""

import os
import stat

import zmq
import zmq.auth


class CurveKeys:
    """A client's key pair and the server's public key (Z85 bytes).

    With `key_file` None the client makes itself a fresh key pair: enough
    for a server without an allow-list (it then only encrypts)."""

    def __init__(self, server_key_file, key_file=None):
        self.server_public = _load(server_key_file, secret=False)[0]
        if key_file is None:
            self.public, self.secret = zmq.curve_keypair()
        else:
            self.public, self.secret = _load(key_file, secret=True)

    def apply(self, socket):
        """Makes `socket` a CURVE client; call before connect()."""
        socket.curve_serverkey = self.server_public
        socket.curve_publickey = self.public
        socket.curve_secretkey = self.secret


def _load(path, secret):
    if secret:
        # As the C++ tools: a secret anyone else may read is no secret.
        mode = os.stat(path).st_mode
        if mode & (stat.S_IRWXG | stat.S_IRWXO):
            raise PermissionError(f"{path}: a secret key must not be accessible to group or "
                                  f"others (chmod 600 {path})")
    try:
        public, secret_key = zmq.auth.load_certificate(path)
    except (ValueError, OSError) as e:
        raise ValueError(f"{path}: not a CURVE key file ({e})") from e
    if public is None or len(public) != 40:
        raise ValueError(f"{path}: no 40-character public-key")
    if secret and (secret_key is None or len(secret_key) != 40):
        raise ValueError(f"{path}: no 40-character secret-key (give NAME.key_secret)")
    return public, secret_key
