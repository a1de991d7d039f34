"""A bound on the messages a Dask connection may announce: the length read from the socket is checked before memory
is allocated for it.

Dask's TCP comm reads an 8-byte length, then allocates that many bytes: a server that is not a Dask scheduler (or a
hostile one) makes the client ask for exabytes.  :func:`bound_frames` wraps the function that allocates, in this
process only, so that a length above :data:`MAX_FRAME_BYTES` ends the connection with :class:`FrameTooLarge`.
tests/reliability/test_bad_scheduler.py checks that the wrapped function is still the one Dask reads with.
"""
from __future__ import annotations

#: Bytes of one message from a scheduler: its largest to a campaign client (the cluster's description, a job's
#: record) is a few kB; 256 MB is far above that and far below what exhausts a machine.
MAX_FRAME_BYTES = 256 * 1024 * 1024


class FrameTooLarge(OSError):
    """The peer announced a message longer than :data:`MAX_FRAME_BYTES`: it is not a Dask scheduler to trust."""


_bounded = False


def bound_frames() -> None:
    """From now on, in this process, a Dask message longer than MAX_FRAME_BYTES is refused before it is allocated."""
    global _bounded
    if _bounded:
        return
    from distributed.comm import tcp

    unbounded = tcp.read_bytes_rw

    async def read_bytes_rw(stream, n: int):
        if not 0 <= n <= MAX_FRAME_BYTES:
            raise FrameTooLarge(f"the peer announced a message of {n:,} bytes, more than the "
                                f"{MAX_FRAME_BYTES // 1024 // 1024} MB a Dask scheduler sends: not a Dask scheduler")
        return await unbounded(stream, n)

    tcp.read_bytes_rw = read_bytes_rw
    _bounded = True
