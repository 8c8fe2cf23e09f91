"""flexmbs.io."""
