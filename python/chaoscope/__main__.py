"""`python -m chaoscope ...`: the command line."""

from ._cli import main

main()
