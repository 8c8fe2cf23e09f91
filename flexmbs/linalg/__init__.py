"""flexmbs.linalg: the compiled factorisation of the iteration matrix (bordered banded LU) and
its plan; below the assembler and the step loop, used by every solver."""
