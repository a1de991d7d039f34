"""A mission run end to end: the generated controller with its codels in a loaded world, its server, the mission.

The controller runs on a virtual clock by default (as fast as the machine
allows; every period still advances the simulation by its own length), or
in real time with ``realtime``.  The world module of the codels package
(``world.py``, ir-sim) is loaded with the world file before the controller
starts, and read back afterwards for the trajectory and the laser's hits.
"""
from __future__ import annotations

import importlib
import os
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from genom2bip.mission.runner import Outcome, Runner
from genom2bip.mission.spec import GOAL_SERVICE, POSE_POSTER, goal_point
from genom2bip.mission.spec import Mission
from runtime.errors import Genom2bipError


#: The controller's events a run keeps (and its trace holds): reports, period overruns, codel errors and codels
#: past their bound (runtime.controller.stuck; real time only).
EVENTS = ("report", "overrun", "codel_error", "codel_overrun")


class WorldError(Genom2bipError):
    """The world file passed the checks, and the simulator refused it still."""


class ViewError(Genom2bipError):
    """``--view``'s page cannot be served (its port is taken)."""


@dataclass
class Run:
    """What a mission run leaves: the outcomes, the controller's reports, the world's record, times."""

    mission: Mission
    world_path: Path | None
    outcomes: list[Outcome]
    events: list[dict[str, Any]] = field(default_factory=list)
    world: Any = None  # the codels' world session (trajectory, hits, obstacles), None without one
    sim_time: float = 0.0
    wall_time: float = 0.0
    error: str | None = None
    codel_times: dict[str, Any] | None = None  # how long each codel ran (runtime.controller.codel_times), if asked
    timing: list[dict[str, Any]] = field(default_factory=list)  # each task's periods, missed, overruns (Timer.stats)
    clock: str = "virtual"  # the controller's clock: virtual (as fast as it can) or real
    goal_ends: dict[int, tuple[float, float]] = field(default_factory=dict)  # true (x, y) at each GoTo's final report

    @property
    def real_time_held(self) -> bool:
        """No period missed, none overran, no codel ran past its bound: the run kept the timing the model has."""
        return not any(t["missed"] or t["overruns"] for t in self.timing) and not any(
            e.get("event") == "codel_overrun" for e in self.events)

    @property
    def expectations_met(self) -> bool:
        return self.error is None and all(o.ok for o in self.outcomes)

    @property
    def ok(self) -> bool:
        """Every expectation met *and* real time held: a run that did not keep its periods proves nothing of the
        robot on time, whatever its requests ended with (docs/missions.md, *The report*)."""
        return self.expectations_met and self.real_time_held


def load_package(directory: str | Path):
    """The generated package in ``directory`` (e.g. gen/dala), imported by its name from its parent folder."""
    directory = Path(os.path.realpath(directory))
    if not (directory / "__init__.py").is_file():
        raise FileNotFoundError(f"{directory}: no generated package here (run genom2bip DESCRIPTIONS -o gen first)")
    parent = str(directory.parent)
    if parent not in sys.path:
        sys.path.insert(0, parent)
    return importlib.import_module(directory.name)


def world_module(controller) -> Any:
    """The ``world`` module beside the codels, None when the codels have none (stand-in codels)."""
    for module in controller.codels.modules.values():
        package = getattr(module, "__package__", None)
        if package:
            try:
                return importlib.import_module(f"{package}.world")
            except ImportError:
                return None
    return None


def navigation_pose(interface: dict[str, Any]) -> dict[str, str] | None:
    """:data:`POSE_POSTER` when the controller has it, else None (the page then draws every poster with a pose)."""
    component, port = POSE_POSTER["poster"].split(".")
    spec = interface["components"].get(component, {}).get("ports", {}).get(port)
    return dict(POSE_POSTER) if spec is not None and spec["direction"] == "out" else None


def scene(mission: Mission, session, interface: dict[str, Any]) -> dict[str, Any]:
    """What the live page draws of the mission (``/scene``): the world's bounds and obstacles, the goals sent,
    the pose poster the robot navigates by."""
    obstacles = []
    for g in session.obstacles():
        if g.geom_type == "Polygon":
            obstacles.append({"kind": "polygon", "points": [[round(x, 3), round(y, 3)] for x, y in g.exterior.coords]})
        else:
            for part in getattr(g, "geoms", [g]):
                obstacles.append({"kind": "line", "points": [[round(x, 3), round(y, 3)] for x, y in part.coords]})
    goals = list({point: None for step in mission.steps if step.kind == "send" and step.target == GOAL_SERVICE
                  and (point := goal_point(step.inputs.get("goal"))) is not None})
    return {"name": mission.name, "bounds": list(session.bounds()), "obstacles": obstacles,
            "goals": [{"x": x, "y": y} for x, y in goals], "pose": navigation_pose(interface)}


def run_mission(mission: Mission, package, codels: Any, world: Path | None, *, realtime: bool = False,
                live: bool = False, log=None, times: bool = False, view: int | None = None,
                token: str | None = None, clock: Any = None) -> Run:
    """Start the controller and its server, load the world, run the mission's steps, stop everything.

    ``times``: record how long each codel runs (``Run.codel_times``).
    ``view``: serve the live page on this port (0: a free one) with the world as its scene, in real time.
    ``token``: what every request to the controller must send (the mission's own requests send it), as ``run``'s.
    ``clock``: the controller's clock (default: a new virtual clock, or the real one as said above).
    """
    from runtime.controller import Controller
    from runtime.controller.timing import VirtualClock
    from runtime.services.client import Client
    from runtime.services.run import find_codels
    from runtime.services.server import ServiceServer

    codels = find_codels(package.INTERFACE, codels, str(Path(package.__file__).parent))
    controller = Controller(package.package(), package.ROOT, package.INTERFACE, codels,
                            clock=clock or (None if realtime or live or view is not None else VirtualClock()),
                            times=times)
    sim_world = world_module(controller)
    try:
        session = sim_world.load(world, display=live) if sim_world is not None and world is not None else None
    except Exception as exc:  # noqa: BLE001 - the simulator's own complaint, about the user's file
        raise WorldError(f"{world}: the simulator cannot load this world: {type(exc).__name__}: {exc}") from None
    shown = scene(mission, session, package.INTERFACE) if view is not None and session is not None else None
    try:
        # bound here: a port taken stops the run now
        server = ServiceServer(controller, port=view or 0, token=token, scene=shown)
    except OSError as exc:
        if session is not None:
            session.close()
        raise ViewError(f"--port {view}: cannot serve the live page there: {exc.strerror or exc}") from None
    events: list[dict[str, Any]] = []
    controller.subscribe(lambda e: events.append(e) if e["event"] in EVENTS else None)
    goal_ends: dict[int, tuple[float, float]] = {}
    if session is not None:
        controller.subscribe(lambda e: _goal_end(e, session, goal_ends))
    started = time.perf_counter()
    controller.start()
    server.start()
    if view is not None:
        print(f"live view: {server.url}/live/ (for as long as the mission runs)", flush=True)
    try:
        outcomes = Runner(Client(server.url, timeout=30, token=token or ""), log).run(mission)
    finally:
        server.stop()
        controller.stop()
    run = Run(mission, world, outcomes, events, session, sim_time=controller.clock.now() - controller.started_at,
              wall_time=time.perf_counter() - started, error=controller.error, codel_times=controller.codel_times(),
              timing=controller.timers.stats(), clock="virtual" if controller.clock.virtual else "real",
              goal_ends=goal_ends)
    if session is not None:
        session.close()
    return run


def _goal_end(event: dict[str, Any], session, ends: dict[int, tuple[float, float]]) -> None:
    """At a GoTo's final report, where the robot truly is (the world's last sample): the report's distance to the
    goal is measured there, not at the trajectory sample of the same time, which lags when periods were missed."""
    if (event.get("event") == "report" and event.get("final")
            and f"{event.get('component')}.{event.get('service')}" == GOAL_SERVICE and session.trajectory):
        last = session.trajectory[-1]
        ends[event["request"]] = (last.x, last.y)


def write_trace(run: Run, path: Path) -> None:
    """The run as JSON lines, in time order: every report of the controller and the robot's true pose."""
    lines: list[tuple[float, int, dict[str, Any]]] = [(e.get("time", 0.0), 0, e) for e in run.events]
    if run.world is not None:
        for s in run.world.trajectory:
            lines.append((s.t, 1, {"event": "pose", "time": s.t, "x": round(s.x, 4), "y": round(s.y, 4),
                                   "theta": round(s.theta, 4), "v": round(s.v, 4), "w": round(s.w, 4)}))
    lines.sort(key=lambda item: (item[0], item[1]))
    tmp = path.with_suffix(path.suffix + ".tmp")
    with tmp.open("w", encoding="utf-8") as f:
        for _, _, event in lines:
            f.write(json.dumps(event, default=str) + "\n")
    tmp.replace(path)
