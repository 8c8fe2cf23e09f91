"""flexmbs.contact."""
