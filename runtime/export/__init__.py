"""Other views of a model: the explored LTS (.aut, DOT), Promela for SPIN, and SPIN runs."""
