"""Safety properties of models too large to explore, by localization reduction with counterexample-guided refinement.

``abstraction`` turns a model into one where a set of atoms stays exact and the
others are a free environment; ``refine`` checks a property on it and grows
the set until the answer is proved or a counterexample replays on the model.
"""
