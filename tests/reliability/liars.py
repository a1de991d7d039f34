"""Servers that answer anything but what a client expects: on 127.0.0.1 only, a bounded number of connections, each
ended when the client hangs up or the test closes the server."""
from __future__ import annotations

import socket
import threading
from typing import Callable


class Liar:
    """A TCP server on 127.0.0.1 answering each connection with ``reply``: bytes, or a function writing to the socket.

    At most ``limit`` connections are served; :attr:`served` counts them; :meth:`close` ends the server.
    """

    def __init__(self, reply: bytes | Callable[[socket.socket], None], limit: int = 50) -> None:
        self.reply, self.limit, self.served = reply, limit, 0
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = self.sock.getsockname()[1]
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        while self.served < self.limit:
            try:
                conn, _ = self.sock.accept()
            except OSError:  # closed: the test is over
                return
            self.served += 1
            with conn:
                try:
                    if callable(self.reply):
                        self.reply(conn)
                    else:
                        conn.sendall(self.reply)
                    conn.shutdown(socket.SHUT_WR)
                    while conn.recv(65536):  # until the client hangs up
                        pass
                except OSError:  # the client hung up first
                    pass

    def close(self) -> None:
        try:
            self.sock.shutdown(socket.SHUT_RDWR)  # wakes the accept() in progress (close alone would not)
        except OSError:
            pass
        self.sock.close()
        self.thread.join()

    def __enter__(self) -> "Liar":
        return self

    def __exit__(self, *exc) -> None:
        self.close()
