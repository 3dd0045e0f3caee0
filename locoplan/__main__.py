"""`python -m locoplan`: the same as the `locoplan` command."""

from locoplan.cli import main

main()
