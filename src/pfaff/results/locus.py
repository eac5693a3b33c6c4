"""The root-locus figure: eigenvalues of a linearization against the parameter varied.

A :class:`pfaff.results.notebook.NotebookFigure`, made without pyplot (see
:mod:`pfaff.results.figures`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def locus_figure(values: np.ndarray, eigenvalues: np.ndarray, label: str = "parameter") -> Figure:
    """Real and imaginary parts of the eigenvalues against the parameter, as Meijaard et al.
    (2007, fig. 3) draw the bicycle's: dots per eigenvalue, the stable half-plane's edge dashed.

    Parameters
    ----------
    values : ndarray, shape (k,)
    eigenvalues : ndarray, shape (k, n)
    label : str
        The parameter's name, for the horizontal axis.

    Examples
    --------
    >>> fig = locus_figure(np.arange(3.0), np.array([[-1, 1j], [-2, 2j], [-3, 3j]]), "v")
    >>> [ax.get_ylabel() for ax in fig.axes]
    ['Re s (1/s)', 'Im s (1/s)']
    """
    from pfaff.results.notebook import NotebookFigure

    values = np.asarray(values, dtype=float)
    eig = np.asarray(eigenvalues, dtype=complex).reshape(len(values), -1)
    fig = NotebookFigure(figsize=(6.4, 5.6), layout="constrained")
    ax_re, ax_im = fig.subplots(2, 1, sharex=True)
    x = np.repeat(values, eig.shape[1])
    ax_re.plot(x, eig.real.ravel(), ".", ms=3, color="C0")
    ax_im.plot(x, np.abs(eig.imag).ravel(), ".", ms=3, color="C1")
    ax_re.axhline(0.0, color="k", lw=0.8, ls="--")
    ax_re.set_ylabel("Re s (1/s)")
    ax_im.set_ylabel("Im s (1/s)")
    ax_im.set_xlabel(label)
    ax_re.set_title("root locus")
    for ax in (ax_re, ax_im):
        ax.grid(True, alpha=0.3)
    return fig
