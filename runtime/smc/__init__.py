"""Statistical model checking: random runs of a tick model (durations drawn, choices weighted) and the estimates
drawn from them (docs/smc.md).  The runs are the exhaustive model's own runs, chosen at random: nothing here adds
to the BIP semantics."""
from runtime.smc.estimates import Estimate, Sprt, chernoff_runs, hoeffding_epsilon
from runtime.smc.sampling import DISTRIBUTIONS, Distribution
from runtime.smc.simulate import Goal, RunOutcome, SimConfig, Simulator, Watch, Window, run_seed

__all__ = ["DISTRIBUTIONS", "Distribution", "Estimate", "Goal", "RunOutcome", "SimConfig", "Simulator", "Sprt",
           "Watch", "Window", "chernoff_runs", "hoeffding_epsilon", "run_seed"]
