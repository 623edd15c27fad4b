"""Markdown tables and number formatting for the report (no NumPy needed)."""
from __future__ import annotations

import math

__all__ = ["fmt", "pct", "markdown_table"]


def fmt(x, digits=3):
    """Compact number: None/nan -> '–', strings unchanged, else %.{digits}g."""
    if x is None:
        return "–"
    if isinstance(x, str):
        return x
    x = float(x)
    if math.isnan(x):
        return "–"
    if math.isinf(x):
        return "inf"
    return f"{x:.{digits}g}"


def pct(x, digits=2):
    """Fraction -> percent string ('0.12 %'); None/nan -> '–'."""
    if x is None or (not isinstance(x, str) and math.isnan(float(x))):
        return "–"
    if isinstance(x, str):
        return x
    return f"{100.0 * float(x):.{digits}g} %"


def markdown_table(header, rows):
    """GitHub table; every row must have as many cells as the header."""
    header = [str(h) for h in header]
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for r in rows:
        if len(r) != len(header):
            raise ValueError(f"row {r!r} has {len(r)} cells, the header {len(header)}")
        out.append("| " + " | ".join(str(c).replace("|", "/") for c in r) + " |")
    return "\n".join(out)
