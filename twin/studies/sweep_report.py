"""What a sweep shows: the table of every point, the Pareto front of its two objectives, the
effect of each parameter, and an HTML page that gathers them.

A design is on the front (non-dominated) when no other design is at least as good in both
objectives and better in one; both objectives are minimized (capture time and error).
"""

from __future__ import annotations

import csv
import html
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from twin.output_format import dumps, format_value
from twin.studies.sweep_file import value_label

__all__ = ["pareto_front", "plot_effects", "plot_front", "write_page", "write_table"]


def pareto_front(objectives: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated rows of ``objectives`` ``(n, m)``, every column minimized.

    Examples
    --------
    >>> pareto_front(np.array([[1.0, 5.0], [2.0, 2.0], [3.0, 3.0], [4.0, 1.0]])).tolist()
    [True, True, False, True]
    """
    values = np.asarray(objectives, np.float64)
    no_worse = (values[:, None, :] <= values[None, :, :]).all(axis=2)
    better = (values[:, None, :] < values[None, :, :]).any(axis=2)
    dominated = (no_worse & better).any(axis=0)
    return np.logical_not(dominated)


def write_table(rows: list[dict], parameters: list[str], measures: list[str], out: Path) -> None:
    """``table.csv`` (one row per point: its number, label, parameter values, measures and
    whether it is on the front) and ``table.json`` (the same rows)."""
    columns = ["point", "label", *parameters, *measures, "on_front"]
    with open(out / "table.csv", "w", newline="", encoding="utf-8") as table:
        writer = csv.writer(table)
        writer.writerow(columns)
        for row in rows:
            values = [row["point"], row["label"]]
            values += [value_label(name, row["values"][name]) for name in parameters]
            values += [f"{row['measures'][name]:.6g}" for name in measures]
            writer.writerow([*values, row["on_front"]])
    (out / "table.json").write_text(dumps(rows), encoding="utf-8")


def plot_front(rows: list[dict], objectives: tuple[str, str], titles: dict, path: Path) -> None:
    """Every design as a point in the objectives' plane; the front joined and labelled."""
    x = np.array([row["measures"][objectives[0]] for row in rows])
    y = np.array([row["measures"][objectives[1]] for row in rows])
    front = np.array([row["on_front"] for row in rows])
    figure = Figure(figsize=(8, 5.5), layout="constrained")
    axes = figure.subplots()
    axes.scatter(x[~front], y[~front], color="0.6", label="dominated design")
    order = np.argsort(x[front])
    axes.plot(x[front][order], y[front][order], "o-", color="tab:red", label="Pareto front")
    for row, xi, yi in zip(rows, x, y, strict=True):
        if row["on_front"]:
            axes.annotate(
                row["label"], (xi, yi), textcoords="offset points", xytext=(6, 4), fontsize=8
            )
    axes.set(
        xlabel=titles[objectives[0]],
        ylabel=titles[objectives[1]],
        title=f"{len(rows)} designs, {int(front.sum())} on the front",
    )
    if x.max() > 8 * x.min() > 0:
        axes.set_xscale("log")
    axes.grid(alpha=0.3)
    axes.legend()
    figure.savefig(path, dpi=110)


def plot_effects(
    rows: list[dict],
    parameters: dict[str, list],
    objectives: tuple[str, str],
    titles: dict,
    path: Path,
) -> None:
    """One panel per parameter and objective: the objective's mean over the other parameters'
    values, with its range (min to max), against the parameter's values."""
    figure = Figure(figsize=(4.2 * len(parameters), 6.5), layout="constrained")
    panels = figure.subplots(2, len(parameters), squeeze=False)
    for column, (name, values) in enumerate(parameters.items()):
        ticks = [value_label(name, value) for value in values]
        for row_index, objective in enumerate(objectives):
            samples = [
                [r["measures"][objective] for r in rows if r["values"][name] == value]
                for value in values
            ]
            means = [np.mean(s) for s in samples]
            axes = panels[row_index, column]
            axes.errorbar(
                range(len(values)),
                means,
                yerr=[
                    [m - min(s) for m, s in zip(means, samples, strict=True)],
                    [max(s) - m for m, s in zip(means, samples, strict=True)],
                ],
                fmt="o-",
                capsize=4,
            )
            axes.set_xticks(range(len(values)), ticks, fontsize=8)
            axes.set(xlabel=name, ylabel=objective if column == 0 else None)
            axes.grid(alpha=0.3)
    figure.suptitle(
        "effect of each parameter, mean and range over the others\n"
        + "\n".join(f"{name}: {titles[name]}" for name in objectives),
        fontsize=9,
    )
    figure.savefig(path, dpi=100)


def write_page(out: Path, summary: dict, rows: list[dict], measures: list[str]) -> Path:
    """``index.html``: the sweep in numbers, the front, the effects and the table."""
    facts = "".join(
        f"<tr><td>{html.escape(str(key))}</td><td>{html.escape(format_value(value))}</td></tr>"
        for key, value in summary.items()
        if key not in ("front", "outputs")
    )
    head = "".join(f"<th>{html.escape(name)}</th>" for name in ("point", "design", *measures))
    bold = ' style="font-weight:bold"'
    body = "".join(
        f"<tr{bold if row['on_front'] else ''}><td>{row['point']}</td>"
        f"<td>{html.escape(row['label'])}</td>"
        + "".join(f"<td>{format_value(row['measures'][name])}</td>" for name in measures)
        + "</tr>"
        for row in rows
    )
    page = (
        "<!DOCTYPE html><html><head><meta charset='utf-8'>"
        f"<title>{html.escape(summary['sweep'])}</title>"
        "<style>body{font-family:sans-serif;max-width:1400px;margin:auto}"
        "td,th{padding:2px 8px;border-bottom:1px solid #ddd;text-align:left}</style></head><body>"
        f"<h1>{html.escape(summary['sweep'])}</h1><table>{facts}</table>"
        "<h2>Capture time against error: the Pareto front</h2>"
        "<p>Designs no other design beats in both objectives are joined and labelled.</p>"
        '<img src="front.png" alt="Pareto front" style="max-width:100%">'
        "<h2>Effect of each parameter</h2>"
        '<img src="effects.png" alt="parameter effects" style="max-width:100%">'
        "<h2>Every design</h2><p>Front designs in bold. All numbers: "
        '<a href="table.csv">table.csv</a>, <a href="table.json">table.json</a>.</p>'
        f"<table><tr>{head}</tr>{body}</table></body></html>"
    )
    path = out / "index.html"
    path.write_text(page, encoding="utf-8")
    return path
