"""Studies over many runs: parameter sweeps (:mod:`.sweep`), tuning (:mod:`.tune`), ablations
(:mod:`.ablate`), their plots (:mod:`.plots`) and HTML reports (:mod:`.report`).

They drive the pipeline through the run layer and score with :mod:`motiontrack.evaluate`; nothing
below this package imports it.
"""
