"""flexmbs: flexible multibody dynamics with ANCF beams and sliding joints with clearance."""

__version__ = "0.1.0"

