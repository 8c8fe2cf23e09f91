"""flexmbs.geometry."""
