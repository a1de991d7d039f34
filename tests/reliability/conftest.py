"""The reliability suite: a generated controller in a process of its own, probed as a user or an attacker would.

Every test here is marked ``reliability`` (``python -m pytest -m reliability`` runs them alone) and waits for
events, never for a time: bounds are far from what a slow machine reaches.
"""
import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
for folder in (HERE, HERE.parent):  # controlproc, flood; runkit
    if str(folder) not in sys.path:
        sys.path.insert(0, str(folder))


def pytest_collection_modifyitems(config, items):
    for item in items:
        if Path(str(item.fspath)).resolve().parent == HERE:
            item.add_marker(pytest.mark.reliability)
