"""flexmbs.elements: the element types (importing the package registers them all)."""

from . import ancf_cable, ancf_rod  # noqa: F401
