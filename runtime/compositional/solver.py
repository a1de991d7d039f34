"""The SAT solver the compositional analysis asks unless told otherwise, in a module of its own: the command line
names it in its help without loading the analysis (networkx, python-sat)."""

#: python-sat's name of the solver (bench/compositional_bench.py measures the others).
DEFAULT_SOLVER = "cadical153"
