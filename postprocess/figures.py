"""Writing figures of post-processing (shared by run and sweep figures)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["save_figures"]


def save_figures(figs: dict[str, Any], folder: Path, formats: Sequence[str]) -> list[Path]:
    """Save every figure as ``folder/<stem>.<format>`` and close it; returns the paths."""
    import matplotlib.pyplot as plt

    folder.mkdir(exist_ok=True)
    written = []
    for stem, fig in figs.items():
        for f in formats:
            p = folder / f"{stem}.{f}"
            fig.savefig(p, dpi=120)
            written.append(p)
        plt.close(fig)
    return written
