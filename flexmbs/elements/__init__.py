"""flexmbs.elements."""
