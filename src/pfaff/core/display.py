"""Short HTML summaries for notebooks: a title and a two-column table, every value escaped.

The results of each stage (:class:`pfaff.Trajectory`, :class:`pfaff.Linearization`,
:class:`pfaff.RootLocus`, a sweep's dataset) build their ``_repr_html_`` from these pieces, so
that they look alike and nothing a user named (a coordinate, an event, a file) reaches the page
unescaped.
"""

from __future__ import annotations

import html
import math
from collections.abc import Iterable


def number(x: float, digits: int = 3) -> str:
    """A number for a summary: ``g`` format, ``e`` below 1e-3 and above 1e5, ``—`` for None.

    Examples
    --------
    >>> number(2.0), number(1.234e-12), number(None), number(float("nan"))
    ('2', '1.23e-12', '—', 'nan')
    """
    if x is None:
        return "—"
    x = float(x) + 0.0  # no "-0"
    if not math.isfinite(x) or x == 0 or 1e-3 <= abs(x) < 1e5:
        return f"{x:.{digits + 1}g}"
    return f"{x:.{digits - 1}e}"


def summary_html(title: str, rows: Iterable[tuple[str, str]], after: str = "") -> str:
    """A titled table of (label, value) rows, both escaped; ``after`` (HTML, already safe) is
    appended below the table.

    Examples
    --------
    >>> page = summary_html("Run <1>", [("status", "success & done")])
    >>> "<strong>Run &lt;1&gt;</strong>" in page, ">success &amp; done</td>" in page
    (True, True)
    """
    body = "".join(
        f'<tr><th style="text-align:left;padding-right:1em">{html.escape(str(k))}</th>'
        f'<td style="text-align:left">{html.escape(str(v))}</td></tr>'
        for k, v in rows
    )
    return (
        f'<div class="pfaff-summary"><strong>{html.escape(title)}</strong>'
        f"<table>{body}</table>{after}</div>"
    )


def table_html(header: Iterable[str], rows: Iterable[Iterable[str]]) -> str:
    """A table with a header row; every cell escaped.

    Examples
    --------
    >>> table_html(["s"], [["-1 < 0"]])
    '<table><tr><th>s</th></tr><tr><td>-1 &lt; 0</td></tr></table>'
    """
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in row) + "</tr>" for row in rows
    )
    return f"<table><tr>{head}</tr>{body}</table>"


def complex_number(z: complex, digits: int = 4) -> str:
    """An eigenvalue for a summary: ``-0.2 + 1.99i``, or the real part alone.

    Examples
    --------
    >>> complex_number(-0.2 - 1.98997j), complex_number(3 + 0j)
    ('-0.2 − 1.99i', '3')
    """
    re, im = number(z.real, digits - 1), number(abs(z.imag), digits - 1)
    if z.imag == 0:
        return re
    return f"{re} {'−' if z.imag < 0 else '+'} {im}i"
