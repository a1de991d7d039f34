"""The simulated world of the DALA codels: an ir-sim world (diff-drive robot, 2D lidar, obstacles) and what it saw.

The physical robot is one ir-sim robot of a world file (descriptions/dala/worlds/).
RFLEX, as the base driver would, sets the wheel command and advances the
simulation by its servo period; LaserRF reads the lidar.  Every other module
sees the robot only through posters.  The session also records what a mission
report needs: the true trajectory, collisions and the laser's hits in the
world frame.

The world is chosen by :func:`load` (the mission runner does), else by the
``DALA_WORLD`` environment variable, else the open field.  Headless unless
``display`` is asked for.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

WORLDS = Path(__file__).resolve().parents[1] / "worlds"
DEFAULT = WORLDS / "open_field.yaml"
HIT_CELL = 0.05  # m: laser hits are kept once per cell of this size


@dataclass
class Sample:
    """The robot's true state at one simulation step."""

    t: float
    x: float
    y: float
    theta: float
    v: float
    w: float


@dataclass
class Session:
    """One loaded world: the ir-sim environment, the wheel command and the record of the run."""

    path: Path
    env: Any
    display: bool = False
    command: tuple[float, float] = (0.0, 0.0)
    t: float = 0.0
    trajectory: list[Sample] = field(default_factory=list)
    collisions: int = 0
    hits: set[tuple[int, int]] = field(default_factory=set)
    render_every: int = 4
    frames: int = 0  # frames drawn in the window (display only)

    @property
    def robot(self) -> Any:
        return self.env.robot_list[0]

    @property
    def step_time(self) -> float:
        return float(self.env.step_time)

    def pose(self) -> dict[str, float]:
        x, y, theta = (float(a) for a in self.robot.state.ravel()[:3])
        return {"x": x, "y": y, "theta": theta}

    def velocity(self) -> dict[str, float]:
        v, w = (float(a) for a in self.robot.velocity.ravel()[:2])
        return {"v": v, "w": w}

    def advance(self, seconds: float) -> None:
        """Apply the wheel command for ``seconds`` (whole simulation steps), recording the trajectory."""
        for _ in range(max(1, round(seconds / self.step_time))):
            self.env.step(list(self.command))
            self.t += self.step_time
            if self.robot.collision:
                self.collisions += 1
            p, s = self.pose(), self.velocity()
            self.trajectory.append(Sample(round(self.t, 6), p["x"], p["y"], p["theta"], s["v"], s["w"]))
            if self.display and len(self.trajectory) % self.render_every == 0:
                self.env.render(0.001)
                self.frames += 1

    def window(self) -> str | None:
        """The matplotlib backend showing the world, None when headless (or when no window could open)."""
        if not self.display:
            return None
        import matplotlib

        backend = matplotlib.get_backend()
        return None if backend.lower() == "agg" else backend

    def scan(self) -> dict[str, Any]:
        """The lidar's last sweep (robot frame); its hits are recorded in the world frame."""
        robot = self.robot
        robot.lidar.step(robot.state[0:3])  # a sweep now, from the current pose
        raw = robot.get_lidar_scan()
        ranges = [float(r) for r in raw["ranges"]]
        top = float(raw["range_max"])
        a0, step = float(raw["angle_min"]), float(raw["angle_increment"])
        p = self.pose()
        for i, r in enumerate(ranges):
            if r < top - 1e-6:
                a = p["theta"] + a0 + i * step
                self.hits.add(
                    (round((p["x"] + r * math.cos(a)) / HIT_CELL), round((p["y"] + r * math.sin(a)) / HIT_CELL))
                )
        return {"angle_min": a0, "angle_step": step, "range_max": top, "ranges": ranges}

    def hit_points(self) -> list[tuple[float, float]]:
        return sorted((i * HIT_CELL, j * HIT_CELL) for i, j in self.hits)

    def obstacles(self) -> list[Any]:
        """The obstacles' shapely geometries, for pictures."""
        return [o.geometry for o in self.env.obstacle_list]

    def bounds(self) -> tuple[float, float, float, float]:
        """xmin, ymin, xmax, ymax of the world."""
        w = self.env._world
        return float(w.x_range[0]), float(w.y_range[0]), float(w.x_range[1]), float(w.y_range[1])

    def close(self) -> None:
        """The simulator's window after a last look (live), and its logging sinks removed now: left to the garbage
        collector, their removal may run inside loguru's ``add`` for the next world, under the lock it holds."""
        if self.display:
            self.env.end(1.0)  # a last look at the window (0 would wait for ever); it closes the logger too
        else:
            self.env.logger.close()  # end() would also clear the world, which the run's pictures still read


_current: dict[str, Session] = {}


def load(path: str | os.PathLike | None = None, display: bool = False) -> Session:
    """Load a world file (default: ``$DALA_WORLD``, else the open field); the robot starts where the file says."""
    import contextlib
    import io
    import warnings

    path = Path(path or os.environ.get("DALA_WORLD") or DEFAULT)
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such world file")
    with warnings.catch_warnings(), contextlib.redirect_stdout(io.StringIO()):
        warnings.simplefilter("ignore")
        import irsim  # on import it tries the interactive backends and prints those it cannot use

        old = _current.get("session")
        if old is not None:  # before the next world's sinks are added
            old.close()
        env = irsim.make(str(path), headless=not display, display=display, log_level="ERROR")
    session = Session(path, env, display)
    robot = session.robot
    if robot.lidar is None:
        raise ValueError(f"{path}: the robot has no lidar2d sensor")
    # The lidar sweeps when LaserRF reads it, not at every physics step of 25 ms (it is most of a step's cost).
    robot.sensors = [s for s in robot.sensors if s is not robot.lidar]
    p = session.pose()
    session.trajectory.append(Sample(0.0, p["x"], p["y"], p["theta"], 0.0, 0.0))
    _current["session"] = session
    return session


def sim() -> Session:
    """The loaded world; the default one is loaded on first use."""
    return _current.get("session") or load()
