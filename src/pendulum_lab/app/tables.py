"""Markdown tables of results, for notebooks and the report's ``summary.md``."""

from __future__ import annotations

__all__ = ["COMPARISON_COLUMNS", "markdown_table"]


#: Columns of :func:`markdown_table`: header, attribute, format.
COMPARISON_COLUMNS = (
    ("pendulum", "pendulum", "{}"),
    ("method", "method", "{}"),
    ("variables", "variables", "{}"),
    ("order", "order", "{}"),
    ("observed order", "observed_order", "{:.2f}"),
    ("max abs(dE), first tenth", "energy_first", "{:.2e}"),
    ("max abs(dE), last tenth", "energy_last", "{:.2e}"),
    ("max abs(dE)/abs(E0)", "max_relative_energy_error", "{:.2e}"),
    ("symplecticity defect", "symplecticity_defect", "{:.1e}"),
    ("reversibility error", "reversibility_error", "{:.1e}"),
    ("iterations/step", "mean_iterations", "{:.1f}"),
    ("evaluations", "evaluations", "{}"),
    ("wall time [s]", "wall_time", "{:.3f}"),
)


def markdown_table(rows, columns=COMPARISON_COLUMNS) -> str:
    """A Markdown (GitHub) table of dataclass rows.

    Parameters
    ----------
    rows : sequence of ComparisonRow, WorkPrecision or any dataclass
    columns : sequence of (header, attribute, format)
        ``format`` is a :meth:`str.format` pattern such as ``"{:.2e}"``.

    Returns
    -------
    str
        Header, separator and one line per row, ending in a newline.
    """
    lines = ["| " + " | ".join(h for h, _, _ in columns) + " |",
             "|" + "|".join("---" for _ in columns) + "|"]
    for row in rows:
        cells = []
        for header, attribute, fmt in columns:
            if not hasattr(row, attribute):
                raise ValueError(f"column {header!r}: a row of type {type(row).__name__} has no "
                                 f"attribute {attribute!r}")
            value = getattr(row, attribute)
            # A comparison row has no observed order where the errors sat at round-off.
            cells.append("round-off" if attribute == "observed_order" and value != value
                         else fmt.format(value))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"
