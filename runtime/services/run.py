"""``python -m <generated package> run``: the controller in real time with its services interface.

Starts the engine thread and the HTTP server on 127.0.0.1 (``--port``,
default a free port, printed), prints reports as they come unless
``--quiet`` (through a console that never waits for its reader:
runtime.services.console), and stops on Ctrl-C or SIGTERM (or ``--duration``
/ ``--limit``): the codel under way finishes (or is interrupted after a few
seconds), the requests still pending get a final report; a second signal
exits at once.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import sys
from pathlib import Path
from typing import Any

from runtime.exits import EXIT_VIOLATED
from runtime.model import Package
from runtime.services.digest import KINDS as DIGESTED
from runtime.services.digest import OverrunDigest
from runtime.services.guard import TOKEN_ENV
from runtime.services.protocol import MAX_CONNECTIONS, READ_TIMEOUT

#: How long the last lines may take to reach an output nobody reads before the command exits anyway (s).
LAST_WORDS = 5.0


class UsageError(Exception):
    """A command-line value that cannot be used: the message names the option."""


def add_arguments(run: argparse.ArgumentParser) -> None:
    run.add_argument("--port", default="0", help="TCP port on 127.0.0.1 (default: a free one, printed)")
    run.add_argument("--host", default="127.0.0.1", metavar="ADDRESS",
                     help="address to listen on (default 127.0.0.1); another one only with a token")
    run.add_argument("--token-file", metavar="FILE",
                     help=f"every client must send 'Authorization: Bearer TOKEN', TOKEN being this file's first "
                          f"line (default: the environment variable {TOKEN_ENV}); never on the command line, "
                          "where ps shows it to every user")
    run.add_argument("--token", help=argparse.SUPPRESS)  # refused with a message: see token_of
    run.add_argument("--read-timeout", type=float, default=READ_TIMEOUT, metavar="SECONDS",
                     help=f"a request must arrive whole within this time of its first byte (default "
                          f"{READ_TIMEOUT:g}); slower clients get 408")
    run.add_argument("--max-connections", type=int, default=MAX_CONNECTIONS, metavar="N",
                     help=f"connections open at once (default {MAX_CONNECTIONS}); one more gets 503")
    run.add_argument("--codels", metavar="DIR|MODULE",
                     help="the codels package (default: codels/ next to the descriptions, see docs/runtime.md)")
    run.add_argument("--connect", metavar="C.IN=D.OUT", action="append", default=[],
                     help="make port in IN of component C read poster OUT of D (default: the poster of that name); "
                          "C.R=D.S makes C's remote R call service S of D (default: the one provider)")
    run.add_argument("--duration", type=float, metavar="SECONDS", help="stop after this many seconds")
    run.add_argument("--limit", type=int, metavar="STEPS", help="stop after this many engine steps")
    run.add_argument("--seed", type=int, help="choose among ready interactions at random with this seed "
                                              "(default: the least recently fired)")
    run.add_argument("--quiet", action="store_true", help="print only the start and the end")
    run.add_argument("--codel-times", metavar="FILE",
                     help="record how long each codel runs (calls; longest, p99 and mean CPU and wall time), write "
                          "it to FILE (JSON) when the run ends and print it with the last lines")
    run.add_argument("--on-violation", metavar="OBSERVER=C.S", action="append", default=[],
                     help="when OBSERVER (its instance path) is violated, request service S of component C "
                          "(e.g. a Stop that interrupts the faulty activity)")


def port_of(text: str) -> int:
    if not text.isdigit() or int(text) > 65535:
        raise UsageError(f"--port {text}: a TCP port from 0 to 65535 expected")
    return int(text)


def token_of(args) -> str | None:
    """The token from ``--token-file`` or the environment; on the command line it is refused."""
    if args.token is not None:
        raise UsageError(f"--token: a token on the command line shows to anyone who lists the processes (ps): "
                         f"give --token-file FILE or set {TOKEN_ENV}")  # the token itself is not repeated
    if args.token_file is None:
        token = os.environ.get(TOKEN_ENV) or None
        where = f"${TOKEN_ENV}"
    else:
        try:
            lines = Path(args.token_file).read_text(encoding="utf-8").splitlines()
        except (OSError, UnicodeDecodeError) as err:
            raise UsageError(f"--token-file {args.token_file}: {getattr(err, 'strerror', None) or err}") from None
        token = lines[0].strip() if lines else ""
        if not token:
            raise UsageError(f"--token-file {args.token_file}: the file holds no token")
        where = f"--token-file {args.token_file}"
    if token is not None and any(c.isspace() or ord(c) < 32 or ord(c) == 127 for c in token):
        raise UsageError(f"{where}: a token cannot hold spaces or control characters (it travels in a header)")
    return token


def find_codels(interface: dict[str, Any], given: str | None, origin: str | None) -> str | None:
    """``--codels``, else the interface's ``codels`` folder: relative to the package (``origin``: its directory or a
    file in it), absolute, or (packages from before) relative to the working directory or a folder above the package.
    """
    if given:
        return given
    recorded = interface.get("codels")
    if not recorded:
        return None
    if origin:
        package = Path(origin).resolve()
        package = package if package.is_dir() else package.parent
        beside = (package / recorded).resolve()
        if beside.is_dir():
            return str(beside)
        if Path(recorded).is_absolute():
            return None
    if Path(recorded).is_dir():
        return recorded
    if origin:
        for folder in Path(origin).resolve().parents:
            if (folder / recorded).is_dir():
                return str(folder / recorded)
    return None


def _line(event: dict[str, Any]) -> str | None:
    kind = event["event"]
    if kind == "report" and event["final"]:
        extra = event.get("outputs") if event["status"] == "ok" else event.get("message")
        text = json.dumps(extra) if isinstance(extra, (dict, list)) else (extra or "")
        return f"[{event['request']}] {event['component']}.{event['service']}: {event['status']} {text}".rstrip()
    if kind in ("overrun", "codel_error", "observer", "codel_overrun"):
        return f"{kind}: {event.get('message')}"
    return None


def exit_now(controller, prog: str, sig: int = signal.SIGINT) -> None:
    """A second Ctrl-C (or SIGTERM): say what is cut short, then leave without waiting for anything."""
    from runtime.services.lastwords import pending_line

    name = "Ctrl-C" if sig == signal.SIGINT else signal.Signals(sig).name
    print(f"{prog}: second {name}: exiting at once; interrupted: {controller.busy() or 'no codel running'}; "
          f"{pending_line(controller)}", file=sys.stderr, flush=True)
    os._exit(128 + sig)


def _build(package: Package, root: str, interface: dict[str, Any], args, origin: str | None):
    """The controller and its server as the options say; :class:`UsageError` for what cannot be used."""
    from runtime.controller import Controller
    from runtime.controller.codel_times import unwritable
    from runtime.controller.recovery import RecoveryError, on_violation
    from runtime.engine import EngineError
    from runtime.services.server import ServiceServer

    port, token = port_of(args.port), token_of(args)
    if any(a.name == "timed" for a in package.annotations):
        raise UsageError("this model is timed (generated with --timed) for verification: its timers wait for "
                         "ticks; generate it with --monitor to run it with its observers")
    why = unwritable(args.codel_times) if args.codel_times else None
    if why:
        raise UsageError(f"--codel-times {args.codel_times}: cannot write it: {why}")
    codels = find_codels(interface, args.codels, origin)
    dotted = args.codels and all(part.isidentifier() for part in args.codels.split("."))
    if args.codels and not Path(args.codels).is_dir() and not dotted:
        raise UsageError(f"--codels {args.codels}: no such directory")
    try:
        controller = Controller(package, root, interface, codels, seed=args.seed, times=bool(args.codel_times))
        for item in args.connect:
            left, _, right = item.partition("=")
            component, _, port_name = left.partition(".")
            if (component, port_name) in controller.remotes.specs:  # a remote: the service it calls
                controller.remotes.connect(component, port_name, right)
            else:
                controller.data.connect(component, port_name, right)
    except EngineError as e:
        raise UsageError(str(e)) from None
    except KeyError as e:
        raise UsageError(f"--connect: {e.args[0]}") from None
    try:
        on_violation(controller, args.on_violation)
    except RecoveryError as e:
        raise UsageError(f"--on-violation: {e}") from None
    try:
        server = ServiceServer(controller, port, args.host, token, args.read_timeout, args.max_connections)
    except ValueError as e:
        raise UsageError(f"--host {args.host}: {e}") from None
    except OSError as e:
        raise UsageError(f"cannot listen on {args.host}:{port}: {e.strerror or e}") from None
    return controller, server


def run_controller(package: Package, root: str, interface: dict[str, Any] | None, args, prog: str,
                   origin: str | None = None) -> int:
    """The ``run`` command: start, serve until stopped, say how it ended; returns the exit status."""
    from runtime.services.console import Console
    from runtime.services.lastwords import guard_exit
    from runtime.services.server import INTERRUPT_GRACE, STOP_GRACE

    if interface is None:
        print(f"{prog}: error: this package has no interface.py (generated by an older genom2bip): regenerate it",
              file=sys.stderr)
        return 1
    try:
        controller, server = _build(package, root, interface, args, origin)
    except UsageError as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 1
    comps = interface["components"]
    nservices = sum(len(c["services"]) for c in comps.values())
    where = controller.codels.where or "none (every codel call fails: give --codels DIR)"
    print(f"{interface.get('system')} controller: {len(comps)} components, {nservices} services; codels: {where}")
    if controller.binder.missing:
        print(f"warning: {len(controller.binder.missing)} codel(s) missing, their services will fail: "
              f"{', '.join(controller.binder.missing)}", file=sys.stderr)
    print(f"services interface on {server.url}/ (OpenAPI: {server.url}/openapi.json, live page: {server.url}/live/); "
          "Ctrl-C stops", flush=True)
    console = Console(sys.stdout, prog=prog)
    digest = OverrunDigest()
    if not args.quiet:
        def show(event: dict[str, Any]) -> None:
            lines = digest.take(event)  # overruns counted, or a count due now
            for text in lines if event["event"] in DIGESTED else [*lines, _line(event)]:
                if text:
                    console.line(text)
        controller.subscribe(show)

    def ended() -> None:
        server.server.should_exit = True  # the run ended by itself (duration, limit, model error): so does the server

    undo = guard_exit(controller, prog)
    server.server.on_force = lambda sig: exit_now(controller, prog, sig)
    controller.start(args.limit, args.duration, then=ended)
    try:
        server.serve()
    except KeyboardInterrupt:
        pass
    controller.stop(timeout=0 if controller.error else STOP_GRACE + INTERRUPT_GRACE)  # abandoned: no wait
    undo()
    for line in digest.flush() + _summary(controller, console):
        console.line(line)
    status = 0
    if args.codel_times and not _write_times(controller, args.codel_times, prog, console):
        status = 1
    console.close(LAST_WORDS)
    if controller.error:
        print(f"{prog}: {controller.error}", file=sys.stderr)
        return EXIT_VIOLATED
    return status


def _write_times(controller, path: str, prog: str, console) -> bool:
    """Write the codel times of the run to ``path``; False (and said why) when it cannot be written."""
    from runtime.controller.codel_times import write_json

    try:
        write_json(path, controller.codel_times())
    except OSError as exc:
        print(f"{prog}: error: --codel-times {path}: cannot write it: {exc.strerror or exc}", file=sys.stderr)
        return False
    console.line(f"wrote {path}")
    return True


def _summary(controller, console) -> list[str]:
    """The last lines: steps and requests by status, lines dropped, codels abandoned and still running."""
    counts = controller.summary()["requests"]
    done = ", ".join(f"{n} {s}" for s, n in sorted(counts.items())) or "none"
    dropped = f"; {console.dropped} output lines dropped (the output was not read)" if console.dropped else ""
    lines = [f"stopped after {controller.steps} steps; requests: {done}{dropped}"]
    lines += [f"still running, abandoned: {what}" for what in controller.abandoned_codels()]
    lines += [f"task {t['task']}: {t['missed']} of {t['periods'] + t['missed']} periods missed, {t['overruns']} "
              f"overran" for t in controller.timers.stats() if t["missed"] or t["overruns"]]
    times = controller.codel_times()
    if times is not None:
        from runtime.controller.codel_times import table

        lines.append("codel times (cpu: the codel thread's CPU time, wall: wall time):")
        lines += ["  " + line for line in table(times)]
    return lines
