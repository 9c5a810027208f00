"""Standalone matplotlib figures, shared by every module that draws one (the experiments' and
the identification's plots). matplotlib is imported lazily; a figure is a
:class:`matplotlib.figure.Figure` saved to a file, so plotting never selects or changes the
global pyplot backend (inline plots in Jupyter keep working)."""

from __future__ import annotations


def new_figure(**kwargs):
    """A standalone figure (no pyplot state): ``Figure(layout="constrained", **kwargs)``."""
    from matplotlib.figure import Figure

    kwargs.setdefault("layout", "constrained")
    return Figure(**kwargs)
