"""Small helpers shared by tests that start a server."""

import socket
import time
import urllib.request


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(url: str, timeout: float = 30.0) -> bytes:
    """The body of ``url`` once it answers 200; fails after ``timeout`` seconds."""
    deadline = time.time() + timeout
    while True:
        try:
            with urllib.request.urlopen(url, timeout=5) as r:
                if r.status == 200:
                    return r.read()
        except OSError:
            if time.time() > deadline:
                raise
        time.sleep(0.2)
