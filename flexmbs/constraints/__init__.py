"""flexmbs.constraints."""
