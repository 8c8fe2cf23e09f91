"""Cross-section and material data of beams."""

from __future__ import annotations

import math
from dataclasses import dataclass

from .errors import ModelError


@dataclass(frozen=True, kw_only=True)
class Material:
    """Linear elastic isotropic material (SI units).

    Parameters
    ----------
    E : float
        Young's modulus [Pa].
    rho : float
        Density [kg/m^3].
    nu : float, default 0.3
        Poisson's ratio (the shear modulus of the rod's torsion, ``G = E / (2 (1 + nu))``).
    """

    E: float
    rho: float
    nu: float = 0.3

    def __post_init__(self) -> None:
        if not (math.isfinite(self.E) and self.E > 0):
            raise ModelError(f"Material: Young's modulus E must be a finite number > 0 "
                             f"(got {self.E!r})")
        if not (math.isfinite(self.rho) and self.rho >= 0):
            raise ModelError(f"Material: density rho must be a finite number >= 0 (got {self.rho!r})")
        if not -1.0 < self.nu < 0.5:
            raise ModelError(f"Material: Poisson ratio nu must be in (-1, 0.5) (got {self.nu})")

    @property
    def G(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))


@dataclass(frozen=True)
class CircularSection:
    """Solid circular cross-section of radius ``radius``.

    Parameters
    ----------
    radius : float
        Radius [m].
    """

    radius: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.radius) and self.radius > 0):
            raise ModelError(f"CircularSection: radius must be a finite number > 0 "
                             f"(got {self.radius!r})")

    @property
    def area(self) -> float:
        return math.pi * self.radius**2

    @property
    def second_moment(self) -> float:
        return math.pi * self.radius**4 / 4.0

    @property
    def polar_moment(self) -> float:
        return math.pi * self.radius**4 / 2.0


@dataclass(frozen=True, kw_only=True)
class BeamStiffness:
    """Beam section resultants given directly: EA [N], EI [N m^2], rho A [kg/m]; optional GJ
    [N m^2] and twist inertia rho J_p [kg m] (the torsion-capable rod's; default for the twist
    inertia: rho A (2 EI)/EA, the polar radius of gyration of a section with I2 = I3 = EI/E),
    and the radius of a circular section (contact, output).

    Parameters
    ----------
    axial_stiffness : float
        EA [N].
    bending_stiffness : float
        EI [N m^2].
    mass_per_length : float
        ρA [kg/m].
    torsional_stiffness : float, optional
        GJ [N m^2] (needed by the rod element).
    radius : float, optional
        Radius of a circular section [m] (contact, output).
    twist_inertia : float, optional
        ρJ_p [kg m] (the rod's; default from EI/EA as above).
    """

    axial_stiffness: float
    bending_stiffness: float
    mass_per_length: float
    torsional_stiffness: float | None = None
    radius: float | None = None  # contact/output radius, if the section is circular
    twist_inertia: float | None = None

    def __post_init__(self) -> None:
        for key in ("axial_stiffness", "bending_stiffness"):
            v = getattr(self, key)
            if not (math.isfinite(v) and v > 0):
                raise ModelError(f"BeamStiffness: {key} must be a finite number > 0 (got {v!r})")
        if not (math.isfinite(self.mass_per_length) and self.mass_per_length >= 0):
            raise ModelError(f"BeamStiffness: mass_per_length must be a finite number >= 0 "
                             f"(got {self.mass_per_length!r})")
        for key in ("torsional_stiffness", "radius"):
            v = getattr(self, key)
            if v is not None and not (math.isfinite(v) and v > 0):
                raise ModelError(f"BeamStiffness: {key} must be a finite number > 0 (got {v!r})")
        v = self.twist_inertia
        if v is not None and not (math.isfinite(v) and v >= 0):
            raise ModelError(f"BeamStiffness: twist_inertia must be a finite number >= 0 (got {v!r})")

    @classmethod
    def from_section(cls, section: CircularSection, material: Material) -> BeamStiffness:
        return cls(
            axial_stiffness=material.E * section.area,
            bending_stiffness=material.E * section.second_moment,
            mass_per_length=material.rho * section.area,
            torsional_stiffness=material.G * section.polar_moment,
            radius=section.radius,
            twist_inertia=material.rho * section.polar_moment,
        )

    @property
    def polar_mass_moment(self) -> float:
        """rho J_p per length [kg m]: :attr:`twist_inertia`, or rho A (2 EI)/EA."""
        if self.twist_inertia is not None:
            return self.twist_inertia
        return self.mass_per_length * 2.0 * self.bending_stiffness / self.axial_stiffness
