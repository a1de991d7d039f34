"""The engine's step and the explorer's search compiled to C (docs/verification/explorer.md, "Compiled exploration").

Generated from the same flat system as the Python step, which stays the
reference: tests check that both give the same successors.  Models the C
back end does not take (floats, strings, nested connectors, externs bound
to Python code) are explored in Python, with a note saying why.
"""
