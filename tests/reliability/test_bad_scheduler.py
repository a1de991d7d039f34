"""``campaign --scheduler``: an address or a time that cannot be used is a usage error (exit 2); a server that is not
a Dask scheduler is refused (exit 1) before the client allocates what its bytes announce; nothing is written."""
from __future__ import annotations

import struct

import pytest

from badinputkit import DALA, genom2bip, tree
from liars import Liar

pytestmark = pytest.mark.reliability

CAMPAIGN = DALA / "campaign.yaml"


@pytest.mark.parametrize("reply", [
    struct.pack("<Q", 3 << 60) + b"\0" * 64,  # a length of 3.5 EB, then nothing of it
    b"HTTP/1.1 200 OK\r\nContent-Length: 2\r\n\r\nok",  # a web server: its first 8 bytes as a length
], ids=["exabytes", "http"])
def test_a_server_that_is_not_a_scheduler_is_refused_before_its_length_is_allocated(tmp_path, reply):
    with Liar(reply) as liar:
        address = f"tcp://127.0.0.1:{liar.port}"
        done = genom2bip("campaign", CAMPAIGN, "-o", tmp_path / "out", "--scheduler", address,
                         "--connect-timeout", "10")
    assert liar.served >= 1  # the client did reach it
    assert done.code == 1, done.err
    assert done.err.startswith(f"genom2bip: error: cannot reach the Dask scheduler {address}: the peer "
                               "announced a message of "), done.err
    assert "more than the 256 MB a Dask scheduler sends: not a Dask scheduler\n" in done.err, done.err
    assert "internal error" not in done.err and "MemoryError" not in done.err
    assert done.peak_mb < 400, done.peak_mb
    assert tree(tmp_path) == []


@pytest.mark.parametrize("address, why", [
    ("http://127.0.0.1:8786", "the scheme is http://"),
    ("tcp://[:::1", "invalid address '[:::1'; maybe: ipv6 needs brackets like [::1]"),
    ("tcp://127.0.0.1", "missing port number in address '127.0.0.1'"),
    ("tcp://127.0.0.1:0", "a host and a port from 1 to 65535 are needed"),
    ("tcp://127.0.0.1:70000", "a host and a port from 1 to 65535 are needed"),
    ("ws://127.0.0.1:1", "the scheme is ws://"),
])
def test_a_scheduler_address_that_cannot_be_used_is_a_usage_error(tmp_path, address, why):
    done = genom2bip("campaign", CAMPAIGN, "-o", tmp_path / "out", "--scheduler", address)
    assert done.code == 2, done.err
    assert done.err == f"genom2bip: error: --scheduler {address!r}: tcp://HOST:PORT or tls://HOST:PORT expected " \
                       f"({why})\n"
    assert tree(tmp_path) == []


@pytest.mark.parametrize("seconds", ["nan", "inf", "-inf", "-1", "0"])
def test_a_connect_timeout_that_is_not_a_time_is_a_usage_error(tmp_path, seconds):
    done = genom2bip("campaign", CAMPAIGN, "-o", tmp_path / "out", "--scheduler", "tcp://127.0.0.1:1",
                     f"--connect-timeout={seconds}")
    assert done.code == 2, done.err
    assert done.err == ("genom2bip: error: --connect-timeout: a number of seconds above 0 and at most 86400 (a day) "
                        f"expected, got {float(seconds):g}\n")
    assert tree(tmp_path) == []


def test_the_bound_wraps_the_function_dask_reads_its_messages_with():
    """The bound lives in Dask's TCP comm: if a new Dask reads otherwise, this says so before a user finds out."""
    import inspect

    from distributed.comm import tcp

    from genom2bip.campaign.frames import bound_frames

    assert "read_bytes_rw(stream, frames_nosplit_nbytes)" in inspect.getsource(tcp.TCP.read)
    bound_frames()
    assert tcp.read_bytes_rw.__module__ == "genom2bip.campaign.frames"
