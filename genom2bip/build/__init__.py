"""From the description IR to the BIP model of the functional level."""
from genom2bip.build.functional import FunctionalLevel, build_package

__all__ = ["FunctionalLevel", "build_package"]
