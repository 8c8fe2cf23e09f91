"""Commands of the ``flexmbs`` CLI that live in their own module (``add_parser`` + ``run``);
:mod:`flexmbs.cli` hooks them in."""
