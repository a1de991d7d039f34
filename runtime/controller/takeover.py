"""The engine going on without a stuck codel: detaching it, firing its step again when it returns, giving up on it.

A mixin of the controller's run (runtime.controller.running); the watchdog,
the bounds and the records are in runtime.controller.stuck.  Only the thread
that is the engine at the moment fires steps; a detached codel's thread only
hands its outcome over and leaves.
"""
from __future__ import annotations

import ctypes
import threading
import time

from runtime.controller.binding import CodelCall, CodelInterrupted
from runtime.controller.stuck import (DEFAULT_BOUND, STARTUP_BOUND, Bound, Detached, Watchdog, atoms_of, bounds,
                                      late_event, overrun_event)


class Takeover:
    """Detached codels of a run: their records, the atoms they freeze, and the watchdog that finds them."""

    detached: list[Detached]
    frozen: set[str]
    _watchdog: Watchdog | None = None
    _step: tuple | None = None
    _taken: tuple | None = None

    def _init_takeover(self) -> None:
        self.detached = []  # steps waiting for their codel (or for being given up on)
        self.abandoned: list[Detached] = []  # given up on while their codel still ran
        self.frozen = set()
        self._bounds = bounds(self.interface)

    # -- the watchdog (its own thread) ------------------------------------------------------------------
    def watch(self) -> None:
        tick = min([b.seconds for b in self._bounds.values()] + [DEFAULT_BOUND]) / 2
        self._watchdog = Watchdog(self.check_codel, max(0.002, min(tick, 0.05))).start()

    def unwatch(self) -> None:
        if self._watchdog is not None:
            self._watchdog.stop()

    def check_codel(self) -> None:
        """The codel under way, if past its bound: reported; detached once it holds something else up."""
        call = self.binder.call
        if call is None or call.done or call.detached:
            return
        bound = self._bounds.get(call.extern, Bound(DEFAULT_BOUND, "the default; no WCET declared"))
        limit = bound.seconds if self.timers.ready else max(bound.seconds, STARTUP_BOUND)
        now = time.monotonic()
        step = self._step
        if now - call.started < limit or step is None:
            return
        inter, info, req, at = step
        d = Detached(call, inter, info, req, self._taken, atoms_of(inter), at)
        task = self._task_of(d)
        if not call.reported:
            call.reported = True
            self.reports.emit(overrun_event(d, bound, task, now))
        if not self._held_up(task) or not call.detach():
            return  # nothing else waits for the engine (yet): the codel keeps it
        with self._lock:
            if self._finished:
                return
            self.detached.append(d)
            self.frozen |= d.atoms
            self._thread = threading.Thread(target=self._drive, name="bip-controller", daemon=True)
            self._thread.start()

    def can_let_go(self) -> bool:
        """The codel under way may wait for the engine (a remote call): the engine runs in a thread it may leave."""
        call = self.binder.call
        return bool(getattr(self, "_threaded", False)) and call is not None and not call.done and (
            call.detached or (call.thread is threading.current_thread() and self._step is not None))

    def let_go(self) -> bool:
        """From the codel under way, about to wait for another component (a remote call): the engine goes on in a
        new thread without it, as for a stuck codel, but at once and without an overrun (False: already so)."""
        call = self.binder.call
        step = self._step
        if call is None or step is None or call.thread is not threading.current_thread() or not call.detach():
            return False
        inter, info, req, at = step
        d = Detached(call, inter, info, req, self._taken, atoms_of(inter), at)
        with self._lock:
            if self._finished:
                return True
            self.detached.append(d)
            self.frozen |= d.atoms
            self._thread = threading.Thread(target=self._drive, name="bip-controller", daemon=True)
            self._thread.start()
        return True

    def _held_up(self, task: str | None) -> bool:
        """Something waits for the engine: another task's period is due, a request is queued, a stop."""
        now = self.clock.now()
        return self._stopping or any(s.queue for s in self.services.values()) or \
            any(t.deadline <= now for t in self.timers.timers if t.task != task)

    def _task_of(self, d: Detached) -> str | None:
        if d.info.scope is not None:
            return d.info.scope.label
        svc = d.info.service
        task = svc.spec.get("task") if svc is not None else None
        return f"{svc.scope.component}.{task}" if task else None

    # -- in the engine thread -------------------------------------------------------------------------------
    def tend(self) -> None:
        """Fire again the steps whose codel has returned; give up on those a waiting request would interrupt."""
        for d in list(self.detached):
            if not d.call.settled:
                who = self._interrupter_waiting(d)
                if who is None:
                    continue
                ran = time.monotonic() - d.call.started
                d.call.abandon(f"codel {d.call.codel} did not return after {ran:.1f} s: abandoned so that {who} "
                               "can run")
                if not d.call.settled:
                    continue
                self.abandoned.append(d)
            self._release(d)
            self._refire(d)

    def _interrupter_waiting(self, d: Detached) -> str | None:
        """A request waiting to interrupt the service of ``d``: its service's name."""
        if d.service is None:
            return None
        for label in self.meanings.interrupters.get(d.service, []):
            svc = self.services.get(label)
            if svc is not None and (svc.queue or (svc.current is not None and svc.current.status == "queued")):
                return label
        return None

    def _release(self, d: Detached) -> None:
        with self._lock:
            self.detached.remove(d)
            self.frozen = set().union(*(x.atoms for x in self.detached))

    def _refire(self, d: Detached) -> None:
        """The step of ``d`` again, from the current state, with the codel's outcome instead of a second call."""
        b = self.binder
        b.failure = None
        if d.taken is not None:  # the step took its request from a queue before the codel: it takes it again
            svc, req = d.taken
            if svc.current is req:
                svc.current = None
            if svc.incoming is req:
                svc.incoming = None
            svc.queue.appendleft(req)
        b.replay[d.call.extern] = d.call
        b.scope, b.locals = d.call.scope, d.call.locals
        self._firing = d.req
        try:
            self.state = self.engine.fire(self.state, d.inter)
        finally:
            b.replay.clear()
            self._firing = None
        self._account(d.inter, d.info, d.req, d.at)

    def settle(self) -> None:
        """At the stop: wait until every detached codel has returned (interrupted) or been given up on."""
        with self._lock:
            self._wake.wait_for(lambda: self._finished or all(d.call.settled for d in self.detached))
            if self._finished:
                return
        for d in list(self.detached):
            self._release(d)
            self._refire(d)

    def left(self, call: CodelCall) -> None:
        """In a detached codel's thread, once it returned: wake the engine; say so if it had been given up on."""
        if call.abandoned is not None:
            d = next((x for x in self.abandoned if x.call is call), None)
            if d is not None:
                self.abandoned.remove(d)
                self.reports.emit(late_event(d, time.monotonic()))
        with self._lock:
            self._epoch += 1
            self._wake.notify_all()

    def give_up(self, why: str) -> None:
        """The stop gives up on every detached codel still running."""
        for d in list(self.detached):
            d.call.abandon(why)
            if d.call.abandoned is not None:
                self.abandoned.append(d)
        with self._lock:
            self._wake.notify_all()

    # -- what a stop or an exit says -----------------------------------------------------------------------
    def busy(self) -> str | None:
        """What a stop waits for: ``codel X of M.S (request N)``, the engine's or a detached one, or None."""
        if self.binder.running is not None:
            return self._current()
        pending = [d for d in self.detached if not d.call.settled]
        return pending[0].describe() if pending else None

    def _current(self) -> str:
        b = self.binder
        scope, req = b.scope, self._firing
        return f"codel {b.running}" + (f" of {scope.label}" if scope is not None else "") + \
            (f" (request {req.id})" if req is not None else "")

    def codel_of(self, thread: threading.Thread) -> str | None:
        """The codel ``thread`` is running, described, or None."""
        call = self.binder.call
        if call is not None and not call.done and call.thread is thread and not call.detached:
            return self._current()
        return next((d.describe() for d in self.detached + self.abandoned if d.call.thread is thread), None)

    def interrupt_codel(self) -> str | None:
        """Raise :class:`CodelInterrupted` in the codels a stop waits for; returns what it interrupted.

        It interrupts Python code only: a codel blocked in a system call
        (``time.sleep``, a read) sees it when the call returns.
        """
        what = self.busy()
        if what is None or not self._stopping:
            return None
        call = self.binder.call
        threads = [d.call.thread for d in self.detached if not d.call.settled]
        if call is not None and not call.done and not call.detached:
            threads.append(call.thread)
        for thread in threads:
            if thread.is_alive():
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(thread.ident),
                                                           ctypes.py_object(CodelInterrupted))
        return what

    def abandoned_codels(self) -> list[str]:
        """The codels given up on whose thread still runs: ``codel X of M.S (request N), for 12.3 s``."""
        now = time.monotonic()
        return [f"{d.describe()}, for {now - d.call.started:.1f} s" for d in self.abandoned
                if not d.call.done and d.call.thread.is_alive()]
