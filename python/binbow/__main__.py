"""`python -m binbow ARGS`: the same as the `binbow ARGS` command (see _cli.py)."""
import sys

from ._cli import main

sys.exit(main())
