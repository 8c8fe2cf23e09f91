"""``python -m flexmbs`` = the ``flexmbs`` command (see :mod:`flexmbs.cli`)."""

import os
import sys

from .cli import EXIT_INTERRUPTED, main

code = main()
if code == EXIT_INTERRUPTED:
    # Under ``python -m``, a Ctrl-C that landed while a library was loading can leave the
    # interpreter's "unhandled KeyboardInterrupt" flag set, and it would then end the process
    # by SIGINT (status -2) although the command handled the interrupt and returned 130. The
    # command's files are closed at this point; leave with its status.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
sys.exit(code)
