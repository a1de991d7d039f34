"""Smaller edges: the generated package's permissions follow the umask; a Host header that is not one is refused;
the local Dask cluster serves no HTTP pages."""
from __future__ import annotations

import os
import stat
import urllib.error
import urllib.request

import pytest

from badinputkit import genom2bip

pytestmark = pytest.mark.reliability

EMPTY = 'component Empty { version "1.0"; lang "c"; };\n'


@pytest.mark.parametrize("umask, mode", [(0o022, 0o755), (0o027, 0o750), (0o002, 0o775)])
def test_the_generated_package_directory_has_the_permissions_the_umask_gives(tmp_path, umask, mode):
    (tmp_path / "Empty.gen").write_text(EMPTY)
    old = os.umask(umask)  # the child inherits it
    try:
        done = genom2bip("generate", tmp_path / "Empty.gen", "-o", tmp_path / "out")
    finally:
        os.umask(old)
    assert done.code == 0, done.err
    package = tmp_path / "out" / "empty"
    assert oct(stat.S_IMODE(package.stat().st_mode)) == oct(mode)
    assert oct(stat.S_IMODE((tmp_path / "out").stat().st_mode)) == oct(mode)


def test_a_package_generated_again_keeps_the_permissions_its_directory_was_given(tmp_path):
    (tmp_path / "Empty.gen").write_text(EMPTY)
    assert genom2bip("generate", tmp_path / "Empty.gen", "-o", tmp_path / "out").code == 0
    package = tmp_path / "out" / "empty"
    package.chmod(0o711)
    assert genom2bip("generate", tmp_path / "Empty.gen", "-o", tmp_path / "out").code == 0
    assert oct(stat.S_IMODE(package.stat().st_mode)) == oct(0o711)


@pytest.mark.parametrize("host", ["127.0.0.1:1@evil.com", "127.0.0.1@evil.com", "127.0.0.1/evil", "127.0.0.1 x",
                                  "[::1]:80@evil.com", "127.0.0.1:", "127.0.0.1:abc"])
def test_a_host_header_that_is_not_a_host_is_refused(host):
    from runtime.services.guard import Guard

    problem = Guard(None).problem({"headers": [(b"host", host.encode())], "method": "GET", "path": "/tasks"})
    assert problem == (400, f"Host {host!r} is not a host name, an address or either with a port: refused")


@pytest.mark.parametrize("host", ["127.0.0.1", "127.0.0.1:8080", "localhost:1", "[::1]:8080", "[::1]"])
def test_a_loopback_host_header_is_taken(host):
    from runtime.services.guard import Guard

    assert Guard(None).problem({"headers": [(b"host", host.encode())], "method": "GET", "path": "/tasks"}) is None


def test_the_local_cluster_serves_no_http_page():
    from genom2bip.campaign.cluster import ClusterSpec, connect

    client, cluster = connect(ClusterSpec(workers=1))
    try:
        info = client.scheduler_info()
        ports = [info.get("services", {}).get("dashboard")]
        ports += [w.get("services", {}).get("dashboard") for w in info["workers"].values()]
        assert len(ports) == 2
        answers = []
        for port in filter(None, ports):
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/health", timeout=30) as reply:
                    answers.append((port, reply.status))
            except urllib.error.HTTPError as exc:
                assert exc.code == 404, (port, exc.code)  # a server with no page
            except urllib.error.URLError as exc:
                assert isinstance(exc.reason, ConnectionRefusedError), exc  # no server at all
        assert answers == []
    finally:
        client.close()
        cluster.close()
