"""``python -m flexmbs`` = the ``flexmbs`` command (see :mod:`flexmbs.cli`)."""

from .cli import console_main

console_main()
