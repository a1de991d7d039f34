"""Devices and FIFOs given where a file is expected: refused by name (exit 1), never read, never waited on.

``/dev/zero`` never ends, so reading it fills memory; a FIFO without a writer
makes ``open`` wait for ever.  The message about such a file must not read it
either (the error printer quotes lines of the files it names).
"""
from __future__ import annotations

import os
import sys
import tempfile
import threading
from pathlib import Path

import pytest

from badinputkit import DALA, ROOT, genom2bip, tree

pytestmark = pytest.mark.reliability

SENSING = DALA / "missions" / "sensing.yaml"
#: Far above what refusing a file costs (about 60 MB), far below what reading /dev/zero reaches under the cap.
PEAK_MB = 400


class Fifo:
    """A FIFO whose writer end waits, in a thread, for a reader: :attr:`opened` tells whether anyone opened it."""

    def __init__(self, path: Path) -> None:
        self.path = path
        os.mkfifo(path)
        self.opened = threading.Event()
        self._writer = threading.Thread(target=self._write, daemon=True)
        self._writer.start()

    def _write(self) -> None:
        with open(self.path, "wb"):  # returns once a reader opens the FIFO; closing gives that reader an end
            self.opened.set()

    def release(self) -> bool:
        """Whether a reader had opened the FIFO; the writer thread is ended either way."""
        was = self.opened.is_set()
        if not was:
            fd = os.open(self.path, os.O_RDONLY | os.O_NONBLOCK)  # the reader the writer waits for
            self._writer.join()
            os.close(fd)
        self._writer.join()
        return was


def _refused(done, path, what: str) -> None:
    assert done.code == 1, done.out + done.err
    assert done.err.startswith(f"{path}: error: cannot read the {what}: not a regular file\n"), done.err
    assert "internal error" not in done.err and "Traceback" not in done.err
    assert done.peak_mb < PEAK_MB, done.peak_mb


def test_a_campaign_file_that_is_dev_zero_is_refused_without_reading_it(tmp_path):
    done = genom2bip("campaign", "/dev/zero", "-o", tmp_path / "out")
    _refused(done, "/dev/zero", "campaign file")
    assert tree(tmp_path) == []


def test_a_mission_file_that_is_dev_zero_is_refused_without_reading_it(tmp_path):
    done = genom2bip("mission", "/dev/zero", "--out", tmp_path / "out", "--quiet")
    _refused(done, "/dev/zero", "mission file")
    assert tree(tmp_path) == []


def test_a_world_that_is_dev_zero_is_refused_without_reading_it(tmp_path):
    done = genom2bip("mission", SENSING, "--world", "/dev/zero", "--out", tmp_path / "out", "--quiet")
    _refused(done, "/dev/zero", "world file")
    assert tree(tmp_path) == []


@pytest.mark.parametrize("verb, what", [("campaign", "campaign file"), ("mission", "mission file"),
                                        ("world", "world file")])
def test_a_fifo_is_refused_without_being_opened(tmp_path, verb, what):
    fifo = Fifo(tmp_path / "in.yaml")
    argv = {"campaign": ("campaign", fifo.path, "-o", tmp_path / "out"),
            "mission": ("mission", fifo.path, "--out", tmp_path / "out", "--quiet"),
            "world": ("mission", SENSING, "--world", fifo.path, "--out", tmp_path / "out", "--quiet")}[verb]
    done = genom2bip(*argv)
    assert not fifo.release(), "the FIFO was opened"
    _refused(done, fifo.path, what)
    assert tree(tmp_path) == ["in.yaml"]


def _runtime_run(*argv) -> tuple[int, str]:
    """``python -m runtime ARGV`` under the same cap as genom2bip children: (exit status, stderr)."""
    import subprocess

    from badinputkit import _capped

    with tempfile.TemporaryFile() as err:
        code = subprocess.call([sys.executable, "-m", "runtime", *map(str, argv)], cwd=ROOT, stdin=subprocess.DEVNULL,
                               stdout=subprocess.DEVNULL, stderr=err, preexec_fn=_capped, timeout=300,
                               env={**os.environ, "PYTHONPATH": str(ROOT)})
        err.seek(0)
        return code, err.read().decode("utf-8", "replace")


def test_runtime_run_refuses_a_model_that_is_dev_zero():
    code, err = _runtime_run("run", "/dev/zero", "--root", "X()")
    assert code == 1, err
    assert err == "/dev/zero: error: cannot read BIP2 file: not a regular file (a device, a pipe or a directory)\n"


def test_runtime_run_refuses_events_that_are_dev_zero():
    model = ROOT / "tests" / "fixtures" / "bip" / "roundtrip" / "rt_extern_ports.bip"
    code, err = _runtime_run("run", model, "--root", "System()", "--events", "/dev/zero", "--limit", "1")
    assert code == 1, err
    assert err == f"{model}: error: /dev/zero: cannot read events: not a regular file (a device, a pipe or a " \
                  "directory)\n", err


def test_the_error_printer_quotes_no_line_of_a_fifo(tmp_path):
    from runtime.diagnostics import Diagnostic, SourceCache, Span

    fifo = Fifo(tmp_path / "f")
    sources = SourceCache()  # /dev/zero is not tried in this process: the old printer would read it all
    assert sources.line(str(fifo.path), 3) is None
    assert Diagnostic(Span(str(fifo.path), 3, 1), "m").render(sources) == f"{fifo.path}:3:1: error: m"
    assert not fifo.release()
