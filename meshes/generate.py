"""Regenerate the gmsh meshes in this folder from their .geo sources (gmsh 4.1 ASCII .msh).

Usage: ``python meshes/generate.py [NAME.geo ...]`` (default: every .geo file here).
Needs the gmsh Python package (``pip install gmsh``); flexmbs itself only reads the .msh files.
"""

from __future__ import annotations

import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def generate(geo: Path) -> Path:
    """Mesh the curves of ``geo`` (1D only) and write ``geo`` with suffix .msh, format 4.1 ASCII."""
    import gmsh

    msh = geo.with_suffix(".msh")
    gmsh.initialize(["-noenv"], readConfigFiles=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.option.setNumber("Mesh.Binary", 0)
        gmsh.option.setNumber("Mesh.SaveAll", 0)  # only elements of physical groups
        gmsh.open(str(geo))
        gmsh.model.mesh.generate(1)
        gmsh.write(str(msh))
    finally:
        gmsh.finalize()
    return msh


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    geos = [Path(a) for a in args] or sorted(HERE.glob("*.geo"))
    for geo in geos:
        print(f"{geo.name} -> {generate(geo).name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
