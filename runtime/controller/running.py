"""The engine thread of a controller: the run loop, its start and its stop, and one step fired with its reports.

Execution uses the engine's own step (``enabled`` then ``fire``), the same
functions the explorer branches on; what real time adds is only *which*
enabled interaction fires and *when* (runtime.controller.choice): when
nothing may fire yet the thread sleeps until the next deadline or until a
request arrives.  A stop ends the run after the step (and codel) under way;
a codel that does not return can be interrupted, then abandoned.  A codel
past its bound is detached and a new engine thread goes on without it
(runtime.controller.takeover).
"""
from __future__ import annotations

import gc
import sys
import threading
from typing import Any, Callable

from runtime.controller.binding import Binder, CodelDetached, CodelInterrupted
from runtime.controller.choice import Choice
from runtime.controller.data import Data
from runtime.controller.meaning import Meanings, StepInfo
from runtime.controller.monitor import Monitor
from runtime.controller.reports import Reports
from runtime.controller.requests import Request
from runtime.controller.takeover import Takeover
from runtime.controller.timing import Timers
from runtime.engine import Engine, Interaction, ModelError

#: The interpreter's switch interval while the engine thread runs (s): a thread woken for a period gets the
#: interpreter back within about this long, even while the services interface is busy (docs/runtime.md).
SWITCH_INTERVAL = 0.001
#: Seconds after which the level counts as started even if a task has not ended its first period.
STARTUP_LIMIT = 30.0


class Running(Takeover):
    """The run of a controller in a thread of its own: base of :class:`~runtime.controller.Controller`.

    The controller's constructor sets what the run works on (below); the
    run sets ``state``, ``steps``, ``status`` (ready, running, stopped,
    error) and ``error``.
    """

    engine: Engine
    clock: Any
    timers: Timers
    monitor: Monitor | None
    binder: Binder
    data: Data
    meanings: Meanings
    choice: Choice
    reports: Reports
    state: tuple | None
    steps: int
    status: str
    error: str | None
    started_at: float | None
    _lock: threading.RLock
    _wake: threading.Condition
    _epoch: int
    _stopping: bool
    _thread: threading.Thread | None
    _firing: Request | None  # the request whose step is under way (to say what a stop cut short)
    _finished: bool

    def start(self, limit: int | None = None, duration: float | None = None,
              then: Callable[[], None] | None = None) -> None:
        """Run in a thread of its own (``stop()`` ends it); ``then()`` is called when the run has ended."""
        self._then = then
        self._threaded = True
        if not self.clock.virtual:
            sys.setswitchinterval(min(sys.getswitchinterval(), SWITCH_INTERVAL))
            # The model, codels and server are built: while the run lasts, full collections leave them out.  A
            # full collection walking them held the interpreter for up to 100 ms, a period missed by any task.
            gc.freeze()
        self._thread = threading.Thread(target=self.run, args=(limit, duration), name="bip-controller", daemon=True)
        self._thread.start()

    def stop(self, timeout: float | None = None) -> None:
        """End the run after the step (and codel) under way; waits (up to ``timeout`` s) for it to have ended."""
        with self._lock:
            self._stopping = True
            self._wake.notify_all()
            self.reports.done.notify_all()  # a codel waiting for a remote's report stops waiting
            if self._thread is None or self._thread is threading.current_thread():
                return
            # the run's end, whichever engine thread it is in (one may have taken over from a stuck codel)
            ended = self._wake.wait_for(lambda: self._finished, timeout)
        thread = self._thread
        if ended and thread is not None and thread is not threading.current_thread():
            thread.join(timeout)

    def run(self, limit: int | None = None, duration: float | None = None) -> str:
        """Run until ``stop()``, ``limit`` steps or ``duration`` seconds; returns the final status."""
        self.started_at = t0 = self.clock.now()
        self._limit, self._end = limit, (t0 + duration if duration is not None else None)
        self.timers.start(t0)
        if self.monitor is not None:
            self.monitor.start(t0)
        self.status = "running"
        if getattr(self, "_threaded", False) and not self.clock.virtual:
            self.watch()
        self.state = self.engine.initial_state()
        return self._drive()

    def _drive(self) -> str:
        """The loop of the engine thread (the first one, or one that took over), then the end of the run."""
        try:
            self._loop()
        except CodelDetached as gone:
            self.left(gone.args[0])  # this thread ran a codel the engine went on without: it is done
            return self.status
        except ModelError as err:
            self.error = f"model error: {err}"
        except CodelInterrupted:
            pass  # a stuck codel was interrupted just after it returned: the stop it was interrupted for goes on
        except Exception as err:  # noqa: BLE001 - a bug here must not leave requests without a report
            self.error = f"internal error: {type(err).__name__}: {err}"
        except BaseException as err:  # SystemExit, KeyboardInterrupt...: the run ends, reported, never silently
            self.error = f"the engine stopped on {type(err).__name__}{f': {err}' if str(err) else ''}"
            self._end_run()
            if threading.current_thread() is threading.main_thread():
                raise
            return self.status
        if not self.error:
            self.settle()  # at the stop: the detached codels return (interrupted) or are abandoned
        self._end_run()
        return self.status

    def _loop(self) -> None:
        """Fire what may fire, else sleep until the next deadline or a request, until told to stop."""
        clock = self.clock
        while True:
            with self._lock:
                if self._stopping:
                    return
                epoch = self._epoch
            if self._limit is not None and self.steps >= self._limit:
                return
            now = clock.now()
            if self._end is not None and now >= self._end:
                return
            if self.detached:
                self.tend()
            if not self.timers.ready and now - self.started_at > STARTUP_LIMIT:
                self.timers.ready_at(now)
            chosen, info, wake_at = self._choose(now)
            if chosen is not None:
                self._fire(chosen, info)
                continue
            if self._end is not None:
                wake_at = self._end if wake_at is None else min(wake_at, self._end)
            if clock.virtual and wake_at is not None:
                clock.advance(wake_at)
                continue
            with self._lock:
                if self._epoch == epoch and not self._stopping:
                    self._wake.wait(None if wake_at is None else max(0.0, wake_at - clock.now()))

    def _end_run(self) -> None:
        """The run has ended in this thread: final reports, then what the starter asked for."""
        self._finish()
        self.unwatch()
        if getattr(self, "_threaded", False):
            if not self.clock.virtual:
                gc.unfreeze()  # what the run left behind is collected as usual
            if self._then is not None:
                self._then()

    def _finish(self) -> None:
        """The run has ended: its status, a final report for every pending request, the ``controller`` event."""
        with self._lock:
            if self._finished:
                return
            self._finished = True
            self._wake.notify_all()
        self.status = "error" if self.error else "stopped"
        self.reports.end_pending(f"the controller stopped ({self.error})" if self.error else "the controller stopped")
        self.reports.emit({"event": "controller", "status": self.status, "steps": self.steps, "error": self.error})

    def alive(self) -> bool:
        """The engine thread is still running (False when run without a thread)."""
        return self._thread is not None and self._thread.is_alive()

    def abandon(self, why: str) -> None:
        """Give up on an engine thread that does not stop: every pending request gets its final report now."""
        with self._lock:
            if self.status != "running" or self._finished:
                return
            self._stopping = True
            self.error = why
        self.give_up(why)
        self._finish()

    def _choose(self, now: float) -> tuple[Interaction | None, StepInfo | None, float | None]:
        """What fires next and when the next period is due (:class:`~runtime.controller.choice.Choice`)."""
        # a request queued while the ready interactions are listed was not seen by them: it is not held (yet)
        seen = self.reports.queue_heads(self.meanings.waits) if self.meanings.waits else {}
        inter, info, wake_at, answerable = self.choice.choose(self.state, now, self.steps, self.frozen)
        if seen:
            self.reports.held(self.meanings.waits, answerable, self.state, seen)
        return inter, info, wake_at

    def _fire(self, inter: Interaction, info: StepInfo) -> None:
        """Fire ``inter`` with its service's or task's codels bound, then report what it did."""
        b = self.binder
        b.failure = None
        svc = info.service
        req = None
        if svc is not None:
            b.scope = svc.scope
            if info.kind in ("trigger", "refuse"):
                req = svc.queue[0] if svc.queue else None
            elif info.kind in ("reject", "preempt"):  # the new request of a service that interrupts itself
                req = svc.incoming or svc.current
            else:
                req = svc.current
            b.locals = req.locals if req is not None else None
        else:
            b.scope, b.locals = info.scope, None
        now = self.clock.now()
        self._firing = req
        self._taken = None
        self._step = (inter, info, req, now)  # what the watchdog detaches if a codel of this step is stuck
        state = self.engine.fire(self.state, inter)  # CodelDetached: another thread is the engine now
        self.state = state
        self._firing = None
        self._account(inter, info, req, now)

    def _account(self, inter: Interaction, info: StepInfo, req: Request | None, now: float) -> None:
        """What a fired step means: a period opened or closed, the level ready, its reports, the observers."""
        self.steps += 1
        timers = self.timers
        if info.opens is not None:
            info.opens.open(now)
        if info.closes is not None:
            overrun = info.closes.close(now)
            if overrun is not None:
                self.reports.emit({"event": "overrun", **overrun})
            if not timers.ready and timers.started_up():
                timers.ready_at(self.clock.now())
        self.reports.after_step(info, req, self.binder.failure, self.state, self.data)
        if self.monitor is not None:
            for event in self.monitor.step(inter.ports, inter.label, now, self.clock.now()):
                self.reports.emit(event)
