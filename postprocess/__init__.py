"""Post-processing of flexmbs output folders: off-screen rendering (pyvista), time-history plots
and hole-section views (matplotlib).

Reads only the files that :mod:`flexmbs.io` writes (``<name>.pvd`` + ``vtu/``, ``probes.csv``,
``contacts.csv``, ``sections.csv``, ``summary.json``); imports nothing from the solvers. pyvista
and matplotlib are imported lazily inside the functions.
"""

from .data import Run, read_run
from .plots import plot
from .render import render
from .section import contact_angles, contact_angles_view, section_figure, section_view
from .sweep import plot_sweep, sweep_figures

__all__ = ["Run", "contact_angles", "contact_angles_view", "plot", "read_run", "render",
           "section_figure", "section_view", "plot_sweep", "sweep_figures"]
