"""flexmbs.solvers."""
