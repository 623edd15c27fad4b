"""PNG plots (matplotlib on an Agg canvas, imported lazily): load-deflection curves, the deformed
shell, a sequence of states."""
from __future__ import annotations

from typing import Mapping, Sequence

import numpy as np

from ..lie import rotation_angle
from ..results.atomic import atomic_path
from .vtk import as_cells, as_frames, as_points

__all__ = ["new_figure", "save_figure", "plot_load_deflection", "plot_shell", "plot_sequence"]


def new_figure(figsize=(6.4, 4.8)):
    """A matplotlib Figure on an Agg canvas (no pyplot, no global backend switch).

    Parameters
    ----------
    figsize : (float, float), optional
        Width and height [inch] (dpi 120).

    Returns
    -------
    matplotlib.figure.Figure

    Example
    -------
    >>> fig = new_figure((3.0, 2.0))
    >>> fig.get_size_inches().tolist(), type(fig.canvas).__name__
    ([3.0, 2.0], 'FigureCanvasAgg')
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=120)
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path, **kw):
    """Save ``fig`` to ``path`` atomically (``results.atomic.atomic_path``): drawn into a
    temporary file beside it and moved into place, so a failed or interrupted save keeps the
    previous image whole (before, ``--plot`` over an earlier image left it truncated, 0 bytes,
    when the save failed).  The format is the extension's (matplotlib's default, png, without
    one); ``kw`` go to ``Figure.savefig``.  Returns the path.

    Example
    -------
    >>> import os, tempfile
    >>> p = save_figure(new_figure((1.0, 1.0)), os.path.join(tempfile.mkdtemp(), "a", "f.png"))
    >>> open(p, "rb").read(4)[1:], os.listdir(os.path.dirname(p))
    (b'PNG', ['f.png'])
    """
    import os
    from matplotlib import rcParams
    fmt = kw.pop("format", None) or os.path.splitext(os.fspath(path))[1].lstrip(".").lower() \
        or rcParams["savefig.format"]
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **kw)
    return os.fspath(path)


def plot_load_deflection(
    path,
    loads,
    displacements: Mapping[str, np.ndarray],
    labels: Mapping[str, str] | Sequence[str] | None = None,
    reference: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    axes: tuple[str, str] = ("displacement [length unit]", "load [load unit]"),
    title: str | None = None,
    secondary: tuple | None = None,
) -> str:
    """Load-deflection curves as a PNG: displacement on x, load on y (as in Sze et al. 2004).

    loads: (k,) load levels; displacements: name -> (k,) computed values, drawn as lines;
    labels: legend text per curve (dict name -> label, or a list in the order of ``displacements``;
    default: the names); reference: name -> (loads, values), drawn as open markers, in the colour of
    the computed curve of the same name if there is one; secondary: (label, values (k,)) a second
    load axis on the right whose ticks give ``values`` at the loads (e.g. the physical load
    beside the load factor). Returns the path.

    Parameters
    ----------
    path : str or path-like
        The PNG file.
    loads, displacements, labels, reference
        As above (ValueError for mismatched lengths).
    axes : (str, str), optional
        The x and y axis labels.
    title : str, optional
        The title.

    Returns
    -------
    str

    Example
    -------
    >>> import os, tempfile
    >>> p = plot_load_deflection(os.path.join(tempfile.mkdtemp(), "ld.png"), [0.0, 0.5, 1.0],
    ...                          {"tip": [0.0, 0.1, 0.3]}, reference={"tip": ([0.0, 1.0], [0.0, 0.3])})
    >>> open(p, "rb").read(4)[1:]                # the PNG signature
    b'PNG'
    """
    loads = np.asarray(loads, dtype=float)
    names = list(displacements)
    if labels is None:
        lab = {k: k for k in names}
    elif isinstance(labels, Mapping):
        lab = {k: labels.get(k, k) for k in names}
    else:
        labels = list(labels)
        if len(labels) != len(names):
            raise ValueError(f"{len(labels)} labels for {len(names)} curves")
        lab = dict(zip(names, labels))

    fig = new_figure()
    ax = fig.add_subplot(1, 1, 1)
    colors = {}
    for i, name in enumerate(names):
        d = np.asarray(displacements[name], dtype=float)
        if d.shape != loads.shape:
            raise ValueError(f"displacements[{name!r}] has shape {d.shape}, loads {loads.shape}")
        (line,) = ax.plot(d, loads, "-", lw=1.6, label=lab[name], color=f"C{i % 10}")
        colors[name] = line.get_color()
    j = len(names)
    for name, (rl, rv) in (reference or {}).items():
        color = colors.get(name)
        if color is None:
            color, j = f"C{j % 10}", j + 1
        ax.plot(np.asarray(rv, float), np.asarray(rl, float), "o", mfc="none", ms=5, color=color,
                label=f"{name} (reference)")
    xlabel, ylabel = axes
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if secondary is not None:
        label, values = secondary
        values = np.asarray(values, float)
        ax2 = ax.twinx()
        ax2.set_ylim(ax.get_ylim())
        ticks = [t for t in ax.get_yticks() if loads.min() - 1e-12 <= t <= loads.max() + 1e-12]
        order = np.argsort(loads)
        ax2.set_yticks(ticks)
        ax2.set_yticklabels([f"{np.interp(t, loads[order], values[order]):.3g}" for t in ticks])
        ax2.set_ylabel(label)
    if title:
        ax.set_title(title)
    ax.grid(True, alpha=0.3)
    if names or reference:
        ax.legend(fontsize="small")
    fig.tight_layout()
    return save_figure(fig, path)


def plot_shell(path, X, quads, g, title: str | None = None, color_by_rotation: bool = True,
               view: tuple = (None, None, 0.0), surfaces=None) -> str:
    """3-D view of the deformed shell (faces = ``quads`` on the current positions ``g[:, :3, 3]``)
    with equal axis scaling, saved as PNG. ``X`` (reference positions, (n, 3)) is drawn as a faint
    wireframe for comparison. Faces are coloured by their mean nodal rotation angle (rad) if
    ``color_by_rotation``. Returns the path.

    Parameters
    ----------
    path : str or path-like
        The PNG file.
    X : (n, 3) array
        Reference positions; ``quads`` (m, 4); ``g`` (n, 4, 4) the current frames.
    title : str, optional
        Figure title; ``color_by_rotation``: colour by rotation angle (else one colour).
    view : (elev, azim, roll), optional
        Camera angles [deg] (roll needs matplotlib >= 3.6; None: matplotlib's default).
    surfaces : list of (name, points (p, 3), quads (q, 4)), optional
        Rigid obstacles, drawn as translucent grey surfaces (``io.obstacle_surfaces``).

    Returns
    -------
    str

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3 import mesh, lie
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> g = lie.exp([0.0, 0.0, 0.0, 0.0, -0.5, 0.0]) @ m.g0            # turned about y
    >>> p = plot_shell(os.path.join(tempfile.mkdtemp(), "shell.png"), m.X, m.quads, g, title="turned")
    >>> os.path.getsize(p) > 0
    True
    """
    import mpl_toolkits.mplot3d  # noqa: F401  (registers the 3d projection)
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    X = as_points(X)
    n = len(X)
    cells = as_cells(quads, n)
    g = as_frames(g, n)
    phi = g[:, :3, 3]
    polys = phi[cells]  # (m, 4, 3)

    fig = new_figure((7.0, 6.0))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    faces = Poly3DCollection(polys, edgecolor="k", linewidths=0.3, alpha=0.9)
    if color_by_rotation:
        import matplotlib.cm as cm
        from matplotlib.colors import Normalize

        ang = rotation_angle(g[:, :3, :3])[cells].mean(axis=1)
        norm = Normalize(vmin=0.0, vmax=max(float(ang.max()), 1e-12))
        faces.set_facecolor(cm.viridis(norm(ang)))
        sm = cm.ScalarMappable(norm=norm, cmap="viridis")
        sm.set_array(ang)
        fig.colorbar(sm, ax=ax, shrink=0.6, label="rotation angle [rad]")
    else:
        faces.set_facecolor("tab:blue")
    ax.add_collection3d(faces)
    extra = []
    for _, pts, quads_s in surfaces or ():
        ax.add_collection3d(Poly3DCollection(np.asarray(pts)[np.asarray(quads_s)], facecolor="0.55",
                                             edgecolor="0.35", linewidths=0.1, alpha=0.25))
        extra.append(np.asarray(pts))
    _finish_3d(ax, X, cells, [phi] + extra, view, title)
    return save_figure(fig, path)


def _finish_3d(ax, X, cells, positions, view, title):
    """The reference outline (dotted), equal axis scaling around every state, camera, labels."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection
    ref = X[cells]
    segs = np.stack([ref, np.roll(ref, -1, axis=1)], axis=2).reshape(-1, 2, 3)
    ax.add_collection3d(Line3DCollection(segs, colors="0.6", linewidths=0.3, linestyles=":"))
    pts = np.vstack(list(positions) + [X])
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre, half = 0.5 * (lo + hi), 0.5 * max(float((hi - lo).max()), 1e-12)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))
    elev, azim, roll = view
    if elev is not None or azim is not None or roll:
        _view(ax, elev, azim, roll)
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.set_zlabel("z")
    if title:
        ax.set_title(title)


def _view(ax, elev, azim, roll=0.0):
    """Camera elevation, azimuth and (matplotlib >= 3.6) roll, in degrees."""
    try:
        ax.view_init(elev=elev, azim=azim, roll=roll)
    except TypeError:          # matplotlib < 3.6: no roll
        ax.view_init(elev=elev, azim=azim)


def plot_sequence(path, X, quads, positions: Sequence[np.ndarray], labels: Sequence[str] | None = None,
                  title: str | None = None, cmap: str = "viridis", view: tuple = (20.0, -60.0, 0.0)) -> str:
    """Several deformed shapes of one shell in one 3-D view (e.g. the states of a load path):
    ``positions[k]`` (n, 3) are the current node positions of state k, drawn as faces coloured
    by k (``cmap``), with a legend of ``labels``; ``X`` (reference) as a dotted outline, equal
    axis scaling; camera ``view`` = (elev, azim, roll) [deg]. Returns the path.

    Parameters
    ----------
    path : str or path-like
        The PNG file.
    X, quads
        The reference mesh; ``positions``: a non-empty sequence of (n, 3) arrays.
    labels : sequence of str, optional
        One per state; ``title``, ``cmap``, ``view`` as above.

    Returns
    -------
    str

    Example
    -------
    >>> import os, tempfile
    >>> from core_se3 import mesh
    >>> m = mesh.rectangle(1.0, 1.0, 2, 1)
    >>> p = plot_sequence(os.path.join(tempfile.mkdtemp(), "seq.png"), m.X, m.quads,
    ...                   [m.X, m.X + [0.0, 0.0, 0.2]], labels=["lam 0", "lam 1"])
    >>> os.path.getsize(p) > 0
    True
    """
    import matplotlib
    import mpl_toolkits.mplot3d  # noqa: F401
    from matplotlib.patches import Patch
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    X = as_points(X)
    cells = as_cells(quads, len(X))
    positions = [as_points(p) for p in positions]
    if not positions:
        raise ValueError("plot_sequence needs at least one state")
    fig = new_figure((7.0, 6.0))
    ax = fig.add_subplot(1, 1, 1, projection="3d")
    colors = matplotlib.colormaps[cmap](np.linspace(0.0, 0.9, len(positions)))
    handles = []
    for k, phi in enumerate(positions):
        if phi.shape != X.shape:
            raise ValueError(f"positions[{k}] has shape {phi.shape}, expected {X.shape}")
        faces = Poly3DCollection(phi[cells], facecolor=colors[k], edgecolor="k", linewidths=0.15, alpha=0.75)
        ax.add_collection3d(faces)
        if labels is not None:
            handles.append(Patch(facecolor=colors[k], label=labels[k]))
    _finish_3d(ax, X, cells, positions, view, title)
    if handles:
        ax.legend(handles=handles, fontsize="x-small", loc="upper left", ncol=2, framealpha=0.6)
    return save_figure(fig, path)
