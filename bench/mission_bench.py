"""How fast a DALA mission runs: robot (simulated) seconds per wall-clock second, on the virtual clock.

    python bench/mission_bench.py [MISSION]      (default: the corridor mission; needs gen/dala)

Prints the mission's robot time, wall time, CPU time (every thread of the process: the controller, its
server, the mission's client) and their ratios, and the cost of a world step and of a lidar sweep measured
on their own.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def main() -> None:
    from genom2bip.mission.session import load_package, run_mission, world_module
    from genom2bip.mission.spec import read_mission

    mission = read_mission(sys.argv[1] if len(sys.argv) > 1 else ROOT / "descriptions/dala/missions/corridor.yaml")
    package = load_package(ROOT / "gen" / "dala")
    cpu = time.process_time()
    run = run_mission(mission, package, str(ROOT / "descriptions/dala/codels"), mission.world)
    cpu = time.process_time() - cpu
    print(f"mission {mission.name}: {run.sim_time:.1f} s robot time in {run.wall_time:.1f} s wall clock "
          f"({run.sim_time / run.wall_time:.2f}x real time), {cpu:.1f} s CPU ({run.sim_time / cpu:.2f} robot s "
          f"per CPU s); expectations met: {run.expectations_met}; real time held: {run.real_time_held}; "
          f"events: {len(run.events)}")
    from runtime.controller import Controller

    c = Controller(package.package(), package.ROOT, package.INTERFACE, str(ROOT / "descriptions/dala/codels"))
    session = world_module(c).load(mission.world)
    t = time.perf_counter()
    for _ in range(400):
        session.advance(0.025)
    step = (time.perf_counter() - t) / 400
    t = time.perf_counter()
    for _ in range(100):
        session.scan()
    sweep = (time.perf_counter() - t) / 100
    print(f"world step (25 ms of robot time): {step * 1e3:.2f} ms; lidar sweep: {sweep * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
