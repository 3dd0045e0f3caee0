"""locoplan: task planner and simulator for humanoid loco-manipulation.

Data flows one way: scenario file -> validated model (`locoplan.scenario`) -> compiled plan
(`locoplan.plan`) -> controller (`locoplan.control`) -> simulator (`locoplan.sim`) ->
log and metrics (`locoplan.log`, `locoplan.metrics`) -> report (`locoplan.report`).
"""

import os as _os

# The controller works on matrices of tens of rows, where BLAS threads only add overhead, and
# on a 2-core machine shared with MuJoCo or other runs they made the closed loop 7x slower
# (measured: 0.14x vs 1.0x real time). Applies only if numpy is not imported yet; the user's
# own setting wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

# Numba caches the compiled kernels next to the sources, or in a per-user folder when the
# installed package is read-only (`locoplan._numba_cache`); decided before numba is imported.
from locoplan import _numba_cache  # noqa: E402

_numba_cache.configure()

__version__ = "0.1.0"
