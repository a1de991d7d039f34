"""A component's C codels in a process of their own: a codel that crashes fails its request, not the controller.

The child process loads the library and calls the codels exactly as :mod:`runtime.ccodels.library` does in
the controller's process; a call goes over a pipe as plain data (the arguments, which of them are ``out``
holders) and comes back as the yield or the exception, with the holders' new values.  When the child dies
during a call (SIGSEGV, abort), the call raises :class:`CodelCrashed` naming the codel and the signal, and a
new child is started in the background for the next call (which waits for it): what the codels kept in
their own static variables is lost, the IDS is not (it lives in the controller).  Each call pays the round
trip (docs/codels.md gives the figure).  A codel's remote call comes back over the same pipe and is made in
the controller, which answers it before the codel's own answer.
"""
from __future__ import annotations

import multiprocessing
import signal
import threading
from typing import Any, Callable

from runtime.genom import Ref, Throw


class CodelCrashed(Exception):
    """The codels' process died while a codel ran; the message names the codel and how the process ended."""


def _serve(conn: Any, component: str, path: str, spec: dict[str, Any]) -> None:
    """The child: load the library, answer calls until the pipe closes."""
    from runtime.ccodels.library import CodelLibrary, CodelLibraryError

    try:
        library = CodelLibrary(component, path, spec)
    except CodelLibraryError as err:
        conn.send(("failed", str(err)))
        return
    conn.send(("ready", None))
    while True:
        try:
            name, plain, refs, remotes = conn.recv()
        except (EOFError, OSError):
            return
        kwargs = {k: (Ref(v) if k in refs else v) for k, v in plain.items()}
        kwargs.update({k: _RemoteProxy(conn, k, parameters) for k, parameters in remotes.items()})
        fn = library.get(name)
        try:
            result = fn(**kwargs)
            answer = ("return", result, None)
        except Throw as thrown:
            answer = ("throw", thrown.name, thrown.detail)
        except Exception as err:  # noqa: BLE001 - said to the controller with the codel's name
            answer = ("error", f"{type(err).__name__}: {err}", None)
        conn.send((*answer, {k: kwargs[k].value for k in refs}))


class _RemoteProxy:
    """In the child: a remote's handle whose call goes back over the pipe to the controller's remote."""

    def __init__(self, conn: Any, arg: str, parameters: list[dict[str, Any]]) -> None:
        self.conn, self.arg, self.parameters = conn, arg, parameters

    def __call__(self, **inputs: Any) -> dict[str, Any]:
        self.conn.send(("remote", self.arg, inputs))
        how, value, detail = self.conn.recv()
        if how == "throw":
            raise Throw(value, detail=detail)
        return value


def _remote_answer(remote: Any, inputs: dict[str, Any]) -> tuple[str, Any, Any]:
    """In the controller: a remote called by a codel of the child, its answer for the pipe."""
    try:
        return "ok", remote(**inputs), None
    except Throw as thrown:
        return "throw", thrown.name, thrown.detail
    except Exception as err:  # noqa: BLE001 - the child's codel gets it as the remote's failure
        return "throw", "genom::remote_io", {"what": f"{type(err).__name__}: {err}"}


class IsolatedLibrary:
    """The codels of one component's library, called in a child process restarted after a crash."""

    def __init__(self, component: str, path: str, spec: dict[str, Any]) -> None:
        from runtime.ccodels.library import CodelLibraryError

        self.component, self.path, self.spec = component, path, spec
        self.context = multiprocessing.get_context("spawn")
        self.lock = threading.Lock()
        self.codels = spec["codels"]
        self.restarts = 0
        self.ready = threading.Event()  # a child serves calls (cleared while a new one starts after a crash)
        self.broken: str | None = None  # why the new child could not serve
        why = self._start()
        if why is not None:
            raise CodelLibraryError(why)
        self.ready.set()

    def _restart(self) -> None:
        """Start a new child in the background: the crashed call reports at once, the next one waits for it."""
        self.ready.clear()

        def start() -> None:
            self.broken = self._start()
            self.ready.set()

        threading.Thread(target=start, name=f"codels-{self.component}-restart", daemon=True).start()

    def _start(self) -> str | None:
        """A new child; why it cannot serve (its library does not load), None when it is ready."""
        parent, child = self.context.Pipe()
        self.process = self.context.Process(target=_serve, args=(child, self.component, self.path, self.spec),
                                            name=f"codels-{self.component}", daemon=True)
        self.process.start()
        child.close()
        self.conn = parent
        try:
            state, why = parent.recv()
        except (EOFError, OSError):
            return f"{self.path}: the process loading the C codels of {self.component} ended before it was ready"
        return why if state == "failed" else None

    def close(self) -> None:
        self.conn.close()
        self.process.join(5)

    def get(self, name: str) -> Callable | None:
        if name not in self.codels:
            return None

        def codel(**kwargs: Any) -> Any:
            return self.call(name, kwargs)

        codel.__name__ = name
        return codel

    def call(self, name: str, kwargs: dict[str, Any]) -> Any:
        refs = [k for k, v in kwargs.items() if isinstance(v, Ref)]
        # a remote's handle stays here: the child's calls of it come back over the pipe and are made here
        remotes = {k: v for k, v in kwargs.items() if callable(v)}
        plain = {k: (v.value if isinstance(v, Ref) else None if callable(v) else v) for k, v in kwargs.items()}
        with self.lock:
            self.ready.wait()
            if self.broken is not None:
                raise CodelCrashed(f"codel {name} of {self.component} cannot run: {self.broken}")
            try:
                self.conn.send((name, plain, refs, {k: getattr(v, "parameters", []) for k, v in remotes.items()}))
                while True:
                    answer = self.conn.recv()
                    if answer[0] != "remote":
                        break
                    self.conn.send(_remote_answer(remotes[answer[1]], answer[2]))
                how, value, detail, written = answer
            except (EOFError, OSError):
                self.process.join(5)
                code = self.process.exitcode
                ended = (f"signal {signal.Signals(-code).name}" if code is not None and code < 0
                         else f"exit status {code}")
                self.restarts += 1
                self._restart()
                raise CodelCrashed(f"codel {name} of {self.component} crashed: its process ended on {ended} "
                                   f"(a new one serves the next calls)") from None
        for k in refs:
            kwargs[k].value = written[k]
        if how == "throw":
            raise Throw(value, detail=detail)
        if how == "error":
            raise CodelCrashed(f"codel {name} of {self.component}: {value}")
        return value
