"""Seeded obstacle worlds for the DALA robot, in the spirit of BARN (Perille et al., 2020), and what makes them hard.

``generate(seed, family)`` draws a world on an occupancy grid (families.py: a
cellular automaton, doorways, corridors, U-shaped traps), keeps it only when
a path with the robot's clearance joins its start to its goal (clearance.py:
a grid search), measures its difficulty along that path (difficulty.py) and
writes it as an ir-sim world file (world_file.py).
"""
from genom2bip.mission.worlds import mission_file, world_file
from genom2bip.mission.worlds.families import FAMILIES, GridWorld, generate

__all__ = ["FAMILIES", "GridWorld", "generate", "mission_file", "world_file"]
