"""`python -m dala run|simulate|describe`: the generated controller on the runtime's engine."""
import sys

from runtime.app import main

from .model import ROOT, package
from .interface import INTERFACE

sys.exit(main(package(), ROOT, prog="python -m dala", interface=INTERFACE, origin=__file__))
