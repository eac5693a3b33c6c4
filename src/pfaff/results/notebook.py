"""The figure pfaff returns: a matplotlib figure that a notebook shows exactly once.

A :class:`matplotlib.figure.Figure` made without pyplot has no display in a fresh Jupyter kernel
(the inline backend registers its PNG printer only once pyplot is imported or ``%matplotlib
inline`` runs), and after ``%matplotlib inline`` a pyplot figure would be shown twice when it is
also returned. :class:`NotebookFigure` displays itself through ``_ipython_display_``, which IPython
asks before any printer: one PNG whatever the backend, and nothing but a line of text for a figure
already written to a file (its picture is there). Outside IPython it is a plain figure.

This module imports matplotlib; the modules that draw import it only when they draw.
"""

from __future__ import annotations

import io
import os
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

PNG_DPI = 100  # the picture shown in a notebook (an 11 × 7 inch figure: 1100 × 700 pixels)


class NotebookFigure(Figure):
    """A :class:`~matplotlib.figure.Figure` shown once in Jupyter, or not at all once written.

    ``written_to`` is the file :func:`pfaff.results.figures.save_figure` wrote it to (None
    until then). Jupyter shows a figure that was not written as one PNG, with or without
    ``%matplotlib inline``; a written one as a line of text naming its file.

    Examples
    --------
    >>> fig = NotebookFigure(figsize=(2, 1))
    >>> fig._repr_png_()[:8] == b"\\x89PNG\\r\\n\\x1a\\n"
    True
    >>> fig.written_to = "run.png"
    >>> fig._repr_png_() is None, fig._repr_mimebundle_()
    (True, {'text/plain': "<Figure written to 'run.png'>"})
    """

    written_to: str | os.PathLike | None = None

    def _repr_png_(self) -> bytes | None:
        """The figure as PNG bytes (None when it was written to a file)."""
        if self.written_to is not None:
            return None
        buf = io.BytesIO()
        self.savefig(buf, format="png", dpi=PNG_DPI)  # laid out already: no tight bbox
        return buf.getvalue()

    def _repr_mimebundle_(self, include: Any = None, exclude: Any = None) -> dict[str, Any]:
        """What a notebook shows: the PNG and a text line, or the text line alone."""
        if self.written_to is not None:
            return {"text/plain": f"<Figure written to {os.fspath(self.written_to)!r}>"}
        return {"image/png": self._repr_png_(), "text/plain": repr(self)}

    def _ipython_display_(self) -> None:
        """Publish :meth:`_repr_mimebundle_` once, ahead of any printer the inline backend
        registered for figures (so ``%matplotlib inline`` does not add a second picture)."""
        from IPython.display import display

        display(self._repr_mimebundle_(), raw=True)


def mark_written(fig: Figure, path: str | os.PathLike) -> None:
    """Record on a :class:`NotebookFigure` that it was written to ``path`` (see the class)."""
    if isinstance(fig, NotebookFigure):
        fig.written_to = Path(path)
