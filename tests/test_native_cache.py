"""The C cache under concurrent builds: two threads of one process (a Dask worker running two jobs) writing the same
library at once both succeed and leave a whole file, never half of one or a stray temporary."""
from __future__ import annotations

import threading

from runtime import cachefiles


def test_two_threads_writing_one_library_at_once_both_succeed_and_leave_a_whole_file(tmp_path, monkeypatch):
    """Thread A has written its temporary file and is about to rename it when thread B writes the same library
    completely; then A renames.  Each writer's temporary file is its own, so both renames succeed."""
    target = tmp_path / "step-x.so"
    a_ready, b_done = threading.Event(), threading.Event()
    rename = cachefiles.os.replace

    def held_replace(src, dst):
        if threading.current_thread().name == "A":
            a_ready.set()
            b_done.wait()
        rename(src, dst)

    monkeypatch.setattr(cachefiles.os, "replace", held_replace)
    failures = []

    def write(data: bytes) -> None:
        try:
            cachefiles.write_atomic(target, data)
        except OSError as exc:
            failures.append(exc)

    a = threading.Thread(target=write, args=(b"A" * 100_000,), name="A")
    a.start()
    a_ready.wait()
    b = threading.Thread(target=write, args=(b"B" * 50_000,), name="B")
    b.start()
    b.join()
    b_done.set()
    a.join()
    assert failures == []
    assert target.read_bytes() == b"A" * 100_000  # A renamed last: its whole file, not B's bytes in A's name
    assert sorted(p.name for p in tmp_path.iterdir()) == ["step-x.so"]
