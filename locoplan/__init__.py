"""locoplan: task planner and simulator for humanoid loco-manipulation.

Data flows one way: scenario file -> validated model (`locoplan.scenario`) -> compiled plan
(`locoplan.plan`) -> controller (`locoplan.control`) -> simulator (`locoplan.sim`) ->
log and metrics (`locoplan.log`, `locoplan.metrics`) -> report (`locoplan.report`).
"""

__version__ = "0.1.0"
