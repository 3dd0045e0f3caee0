"""`python -m locoplan.cli ...`: the same as the `locoplan` console script."""

from locoplan.cli import main

main()
