"""Draw the shape generators of core_se3.mesh (docs/SCENARIOS.md): docs/figures/shape_NAME.png.

    python docs/figures/shapes.py [structured|gmsh]      (default structured)

Each picture shows the mesh of one generator, its regions in colours and its named node sets
as dots with their names.
"""
import os
import sys

import numpy as np

from core_se3 import mesh as M
from core_se3.io.plots import new_figure

HERE = os.path.dirname(os.path.abspath(__file__))
SHAPES = {
    "star": ("star(5, 20, 6, size=1.5)", lambda b: M.star(5, 20.0, 6.0, size=1.5, backend=b)),
    "cross": ("star(4, 20, 6, palm=6, size=1.5)", lambda b: M.star(4, 20.0, 6.0, palm=6.0, size=1.5, backend=b)),
    "polygon": ("polygon(6, 10, size=2)", lambda b: M.polygon(6, 10.0, size=2.0, backend=b)),
    "rounded_rectangle": ("rounded_rectangle(30, 16, 4, size=2)",
                          lambda b: M.rounded_rectangle(30.0, 16.0, 4.0, size=2.0, backend=b)),
    "disk": ("disk(10, size=2)", lambda b: M.disk(10.0, size=2.0, backend=b)),
    "annulus_sector": ("annulus_sector(6, 12, 2.5, size=1.2)",
                       lambda b: M.annulus_sector(6.0, 12.0, 2.5, size=1.2, backend=b)),
}


def draw(path, m, title):
    from matplotlib.collections import PolyCollection
    fig = new_figure((4.2, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    colour = np.zeros(m.n_elements)
    names = sorted(k for k in m.regions if k not in ("fingers",))
    for i, name in enumerate(names):
        colour[m.regions[name]] = i
    pc = PolyCollection(m.X[m.quads][:, :, :2], array=colour, cmap="Pastel1", edgecolors="0.3", linewidths=0.4)
    ax.add_collection(pc)
    for i, (name, ids) in enumerate(sorted(m.edges.items())):
        if name in ("tips", "boundary"):
            continue
        P = m.X[ids]
        ax.plot(P[:, 0], P[:, 1], ".", ms=3, color=f"C{i % 10}")
        c = P.mean(0)
        ax.annotate(name, c[:2], fontsize=6, color=f"C{i % 10}", ha="center", va="center")
    for name in names:
        c = m.X[m.quads[m.regions[name]]].mean((0, 1))
        ax.annotate(name, c[:2], fontsize=7, ha="center", va="center", weight="bold")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_title(f"{title}: {m.n_elements} quads", fontsize=8)
    ax.set_axis_off()
    fig.tight_layout()
    fig.savefig(path)
    from PIL import Image                      # a 64-colour palette keeps each picture small
    Image.open(path).convert("RGB").quantize(64).save(path, optimize=True)


if __name__ == "__main__":
    backend = sys.argv[1] if len(sys.argv) > 1 else "structured"
    for name, (title, make) in SHAPES.items():
        path = os.path.join(HERE, f"shape_{name}.png")
        draw(path, make(backend), title)
        print("wrote", path)
