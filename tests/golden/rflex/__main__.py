"""`python -m rflex run|describe`: the generated controller on the runtime's engine."""
import sys

from runtime.app import main

from .model import ROOT, package

sys.exit(main(package(), ROOT, prog="python -m rflex"))
