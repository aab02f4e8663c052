"""read, write, info, validate and the merge-tree statistics of .gtn files."""

import os
import warnings

import numpy as np

from . import _gatun
from ._errors import DamagedChunkWarning


class Mesh:
    """A tetrahedral mesh read from a .gtn file.

    points      (n, 3) array in the stored precision (float32 or float64)
    tets        (m, 4) uint32 array of point indices, positively oriented
    point_data  dict name -> (n,) or (n, components) array in the field's stored type
    cell_data   dict name -> (m,) or (m, components) array in the field's stored type
    metadata    dict str -> str, the file's metadata
    level       the stored level decoded (the one simplified further on the fly for a ratio)
    merges      merges of level 0's merge tree applied (0: the lossless mesh)
    ratio       merges / points of level 0
    pieces      the stored level's pieces decoded (increasing indices; every piece for a whole
                level); None for a mesh simplified on the fly
    point_ids   of a part of a stored level (a read with box or pieces): (n,) uint32 array, the level's
                numbers of the points (the indices a whole read of the level gives them); else None
    tet_ids     likewise (m,) uint64 array, the level's numbers of the tetrahedra; else None
    """

    __slots__ = ("points", "tets", "point_data", "cell_data", "metadata", "level", "merges", "ratio", "pieces",
                 "point_ids", "tet_ids")

    def __init__(self, points, tets, point_data=None, cell_data=None, metadata=None, level=0, merges=0, ratio=0.0,
                 pieces=None, point_ids=None, tet_ids=None):
        self.points = points
        self.tets = tets
        self.point_data = dict(point_data or {})
        self.cell_data = dict(cell_data or {})
        self.metadata = dict(metadata or {})
        self.level = level
        self.merges = merges
        self.ratio = ratio
        self.pieces = pieces
        self.point_ids = point_ids
        self.tet_ids = tet_ids

    def __repr__(self):
        return (
            f"<gatun.Mesh: {len(self.points)} points ({self.points.dtype}), {len(self.tets)} tetrahedra, "
            f"point data {sorted(self.point_data)}, cell data {sorted(self.cell_data)}, level {self.level}, "
            f"ratio {self.ratio:.4g}>"
        )


def read(path, level=None, ratio=None, fields=None, box=None, pieces=None, threads=None):
    """Reads a .gtn file.

    level   a stored level (0 = the lossless mesh, the default)
    ratio   a simplification ratio in [0, 1] (vertices merged away / vertices of level 0): the finest
            stored level not beyond it, simplified on the fly with its merge tree, as `gtn export
            --ratio`; a ratio beyond what the tree allows gives the coarsest mesh
    fields  names of the point and cell fields to decode (default: all; the others are not decoded)
    box     (xmin, ymin, zmin, xmax, ymax, zmax): only the tetrahedra that meet this box, with the
            points they use. Of a stored level only the pieces whose bounding boxes meet the box are
            decoded, then filtered; with a ratio the simplified mesh is decoded whole, then filtered.
    pieces  indices of the stored level's pieces to decode (gatun.info(path)["levels"][i]["pieces"]
            is the piece table: tetrahedra and bounding box of each): their tetrahedra, stitched
            (seam points once). With box, the pieces named that meet it. Not with ratio.
            Reads of a part (box, pieces) give the level's numbers of their points and tetrahedra in
            mesh.point_ids and mesh.tet_ids, and mesh.pieces the pieces decoded.
    threads the most threads the library's parallel parts (TBB) may use during the call (default: every
            core): a level of several pieces decodes them in parallel; gatun.write's threads bounds
            the ranking and the check.

    The arrays are handed over from the decoder without a copy (float32 coordinates are narrowed from
    the decoder's doubles once). Raises a gatun.Error subclass with the message `gtn` would print.
    Every chunk's checksum is checked, as `gtn export` does: damage in a chunk the read does not need
    (another level, the merge tree) is a gatun.DamagedChunkWarning with gtn's warning text.
    """
    if level is not None and ratio is not None:
        raise _usage(f"{os.fspath(path)}: level and ratio exclude each other")
    if isinstance(fields, str):
        fields = [fields]
    d = _gatun.read(
        os.fspath(path),
        level=None if level is None else int(level),
        ratio=None if ratio is None else float(ratio),
        fields=None if fields is None else [str(f) for f in fields],
        box=None if box is None else [float(v) for v in box],
        pieces=None if pieces is None else [int(p) for p in np.atleast_1d(pieces)],
        threads=None if threads is None else int(threads),
    )
    for message in d["warnings"]:
        warnings.warn(DamagedChunkWarning(message), stacklevel=2)
    return Mesh(
        d["points"], d["tets"], d["point_data"], d["cell_data"], d["metadata"], d["level"], d["merges"], d["ratio"],
        d["pieces"], d["point_ids"], d["tet_ids"]
    )


def write(
    path,
    points,
    tets,
    point_data=None,
    cell_data=None,
    levels=None,
    *,
    metadata=None,
    merge_tree=True,
    level_storage=2.0,
    verify=True,
    simplify_field="",
    w_density=1.0,
    w_geometry=1.0,
    greedy_ranking=False,
    keep_invalid=False,
    threads=None,
):
    """Writes a .gtn file as `gtn convert` does, with the same defaults.

    points      (n, 3) float32 or float64 array (the file keeps that precision)
    tets        (m, 4) integer array of point indices (inverted tetrahedra are turned around, with a warning)
    point_data  dict name -> (n,) or (n, components) array of int8..uint64, float32 or float64
    cell_data   dict name -> (m,) or (m, components) array
    levels      mip levels beyond level 0 (None: automatic, within level_storage times level 0's bytes)
    merge_tree  store the merge trees (on-the-fly simplification); False = --no-merge-tree (level 0 alone)
    verify      decode every level back and compare before the file is renamed into place
    simplify_field, w_density, w_geometry: the ranking's density field and weights (--simplify-field ...)
    greedy_ranking  rank in one queue, in the greedy order (--greedy-ranking)
    keep_invalid  write a mesh with errors of its own that validate() reports (--keep-invalid); by default
                such a mesh raises gatun.InvalidDataError and nothing is written
    threads     the most threads the ranking and the check may use (default: every core)

    The file appears atomically, only when everything succeeded.
    """
    if levels is not None and not 0 <= int(levels) <= 62:
        raise _usage(f"{os.fspath(path)}: levels {levels} is not in 0..62")
    points = np.asarray(points)
    if points.dtype.kind in "iub":
        points = points.astype(np.float64)
    found = _gatun.write(
        os.fspath(path),
        _little(points),
        np.asarray(tets),
        {str(k): _little(np.asarray(v)) for k, v in (point_data or {}).items()},
        {str(k): _little(np.asarray(v)) for k, v in (cell_data or {}).items()},
        {str(k): str(v) for k, v in (metadata or {}).items()},
        -1 if levels is None else int(levels),
        bool(merge_tree),
        float(level_storage),
        bool(verify),
        str(simplify_field),
        float(w_density),
        float(w_geometry),
        bool(greedy_ranking),
        bool(keep_invalid),
        None if threads is None else int(threads),
    )
    for message in found:
        warnings.warn(message, stacklevel=2)


def info(path, merge_tree=False):
    """The object `gtn info --json [--merge-tree]` prints, as a dict. `path`: a .gtn file, or a mesh
    file (or a list of files, e.g. a PLOT3D grid and its Q file) as `gtn convert` reads them."""
    inputs = [os.fspath(p) for p in path] if isinstance(path, (list, tuple)) else [os.fspath(path)]
    return _gatun.info(inputs, bool(merge_tree))


def validate(path, against=None, quick=False, max_issues=100):
    """The report `gtn validate --json` prints, as a dict (its "errors" count says whether the file
    passed). against: source file(s) that level 0 must equal; quick: container and checksums only."""
    if isinstance(against, (str, os.PathLike)):
        against = [against]
    report, _ = _gatun.validate(os.fspath(path), [os.fspath(a) for a in against or []], bool(quick), int(max_issues))
    return report


def merge_tree_stats(path):
    """Statistics of the file's merge trees, as `gtn info --json --merge-tree` reports them under
    "merge_tree": merges, roots, depth, fan-out, error quantiles, per stored level (ratio, tetrahedra,
    bytes, largest error) and the error curve (error against ratio). None when the file stores none."""
    return _gatun.merge_tree(os.fspath(path))


def plot_merge_tree(path, out_png=None, ax=None):
    """Draws the merge error against the simplification ratio with the stored levels marked, as
    `gtn info --plot` does, with matplotlib. Returns the figure; saves it to out_png (800 x 500
    pixels) when given."""
    import matplotlib

    if ax is None and out_png is not None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    stats = merge_tree_stats(path)
    name = os.fspath(path)
    if stats is None:
        raise _usage(f"{name}: the file stores no merge tree (written with --no-merge-tree)")
    curve = stats["error_curve"]
    if not curve:
        raise _usage(f"{name}: the merge tree stores no error quantiles (no merges, or written without them)")
    if ax is None:
        fig, ax = plt.subplots(figsize=(8, 5), dpi=100)
    else:
        fig = ax.figure
    ratios = [p["ratio"] for p in curve]
    errors = [p["error"] for p in curve]
    largest = [p["largest_error"] for p in curve]
    ax.step(ratios, largest, where="post", lw=2, color="tab:blue", label="largest merge error up to the ratio")
    ax.plot(ratios, errors, "o", ms=3, color="#9ecae1", label="error quantiles of each stored level's merge tree")
    marked = [(lv["ratio"], lv["largest_error"]) for lv in stats["levels"] if lv["largest_error"] is not None]
    if marked:
        ax.plot([m[0] for m in marked], [m[1] for m in marked], "s", color="tab:red", label="stored levels: largest error")
    for lv in stats["levels"]:
        if lv["level"] > 0:
            ax.axvline(lv["ratio"], color="0.55", ls="--", lw=0.8)
            ax.annotate(f"level {lv['level']}", (lv["ratio"], 0.03), xycoords=("data", "axes fraction"),
                        rotation=90, color="0.35", fontsize=8, ha="right")
    positive = [e for e in errors if e > 0]
    if positive and max(errors) / min(positive) > 100:
        ax.set_yscale("log")
    ax.set_xlim(0, 1)
    ax.set_xlabel("simplification ratio (vertices merged away / vertices of level 0)")
    ax.set_ylabel("merge error")
    ax.set_title(f"{name}: merge error against simplification ratio")
    ax.grid(True, alpha=0.4)
    ax.legend(loc="upper left")
    if out_png is not None:
        fig.savefig(os.fspath(out_png), dpi=100)
    return fig


def _little(a):
    """The array with little-endian values, as the file stores them."""
    if a.dtype.byteorder == ">":
        return a.astype(a.dtype.newbyteorder("<"))
    return a


def _usage(message):
    from ._errors import UsageError

    return UsageError(message)
