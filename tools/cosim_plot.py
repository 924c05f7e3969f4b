#!/usr/bin/env python3
"""Draws the figures of `cosim plot` and `cosim sweep` with matplotlib.

cosim writes a JSON description of the figures and runs

    python3 cosim_plot.py FIGURES.json    draw every figure of the file (PNG)
    python3 cosim_plot.py --check         exit 0 when matplotlib can be imported

FIGURES.json: {"figures": [{"file": "a.png", "title": ..., "xlabel": ..., "ylabel": ...,
"xscale": "linear" | "log", "yscale": ..., "panels": [...]}]}. A figure without "panels" is one
panel; each panel has "title", "xlabel", "ylabel", "xscale", "yscale" and "lines", each line
{"label", "x", "y", "style": "line" | "reference" | "points" | "hline", "annotations": [...]}.

Exit codes: 0 drawn, 3 matplotlib missing, 2 anything else.
"""
import json
import math
import sys

MISSING_MATPLOTLIB = 3


def load_matplotlib():
    try:
        import matplotlib

        matplotlib.use("Agg")  # files only, no display needed
        import matplotlib.pyplot as plt
    except ImportError as error:
        print(f"cosim_plot: matplotlib is missing ({error}); on Debian: "
              "apt-get install python3-matplotlib", file=sys.stderr)
        sys.exit(MISSING_MATPLOTLIB)
    return plt


def draw_panel(ax, panel):
    ax.set_title(panel.get("title", ""), fontsize=9)
    ax.set_xlabel(panel.get("xlabel", ""))
    ax.set_ylabel(panel.get("ylabel", ""))
    labelled = 0
    for line in panel.get("lines", []):
        style = line.get("style", "line")
        label = line.get("label")
        labelled += 1 if label else 0
        x, y = line.get("x", []), line.get("y", [])
        if style == "hline":
            ax.axhline(y[0], linestyle="--", linewidth=1.2, color=line.get("color"), label=label)
            continue
        if style == "reference":
            ax.plot(x, y, linestyle="--", linewidth=1.5, color="black", label=label)
        elif style == "points":
            # In order of cost, so the curve reads as error against run time.
            order = sorted(range(len(x)), key=lambda i: x[i])
            notes = line.get("annotations", [])
            x, y = [x[i] for i in order], [y[i] for i in order]
            notes = [notes[i] for i in order] if len(notes) == len(order) else []
            ax.plot(x, y, marker="o", linewidth=1.0, label=label)
            for xi, yi, text in zip(x, y, notes):
                ax.annotate(text, (xi, yi), textcoords="offset points", xytext=(4, 4),
                            fontsize=7)
        else:
            ax.plot(x, y, linewidth=1.2, label=label, marker="." if len(x) < 30 else None)
    positive = all(v > 0 for line in panel.get("lines", []) for v in line.get("x", []))
    if panel.get("xscale") == "log" and positive:
        ax.set_xscale("log")
    positive = all(v > 0 and math.isfinite(v)
                   for line in panel.get("lines", []) for v in line.get("y", []))
    if panel.get("yscale") == "log" and positive:
        ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    if labelled > 1 or (labelled == 1 and not panel.get("title")):
        ax.legend(fontsize=7)


def draw(plt, figure):
    panels = figure.get("panels") or [figure]
    columns = min(3, len(panels))
    rows = (len(panels) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(5.5 * columns, 3.8 * rows), squeeze=False)
    for ax, panel in zip(axes.flat, panels):
        draw_panel(ax, panel)
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    if figure.get("panels") and figure.get("title"):
        fig.suptitle(figure["title"])
    fig.tight_layout()
    fig.savefig(figure["file"], dpi=110)
    plt.close(fig)
    print(figure["file"])


def main(argv):
    if len(argv) == 2 and argv[1] == "--check":
        load_matplotlib()
        return 0
    if len(argv) != 2:
        print(__doc__, file=sys.stderr)
        return 2
    plt = load_matplotlib()
    with open(argv[1], encoding="utf-8") as f:
        spec = json.load(f)
    for figure in spec["figures"]:
        draw(plt, figure)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
