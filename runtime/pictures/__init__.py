"""Pictures of a BIP model and of its traces: DOT text, rendered to SVG or PNG (docs/pictures.md).

A back end over the flat system and over traces, never over the builder:
``structure`` derives what to draw, ``architecture`` draws the functional
level and one module, ``automaton`` one atom, ``sequence`` a trace, and
``render`` writes the file a user asked for.
"""
from runtime.pictures.architecture import functional_level, module
from runtime.pictures.automaton import automaton
from runtime.pictures.outline import outline
from runtime.pictures.render import PictureError, layout, layout_command, render
from runtime.pictures.sequence import sequence
from runtime.pictures.structure import Structure, structure

__all__ = [
    "PictureError",
    "Structure",
    "automaton",
    "functional_level",
    "layout",
    "layout_command",
    "module",
    "outline",
    "render",
    "sequence",
    "structure",
]
