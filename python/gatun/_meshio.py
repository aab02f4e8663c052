"""The .gtn format in meshio: meshio.read("x.gtn") and meshio.write("x.gtn", mesh).

Reading gives one "tetra" cell block with the point data and the cell data ({name: [array]}) of level 0.
Writing takes tetra cell blocks only (several are joined in order, their cell data with them); any
other cell type is refused with a gatun.UsageError naming it.
"""

import numpy as np

from . import _mesh
from ._errors import UsageError


def read(filename):
    import meshio

    m = _mesh.read(filename)
    return meshio.Mesh(
        m.points,
        [("tetra", m.tets)],
        point_data=m.point_data,
        cell_data={name: [values] for name, values in m.cell_data.items()},
        field_data={},
    )


def write(filename, mesh, **kwargs):
    others = sorted({block.type for block in mesh.cells if block.type != "tetra"})
    if others:
        counts = ", ".join(
            f"{sum(len(b.data) for b in mesh.cells if b.type == t)} {t}" for t in others
        )
        raise UsageError(f"{filename}: .gtn holds tetrahedra only; the mesh has other cells ({counts})")
    blocks = [i for i, block in enumerate(mesh.cells) if block.type == "tetra"]
    tets = np.concatenate([mesh.cells[i].data for i in blocks]) if blocks else np.zeros((0, 4), np.int64)
    cell_data = {}
    for name, per_block in mesh.cell_data.items():
        cell_data[name] = np.concatenate([np.asarray(per_block[i]) for i in blocks]) if blocks else np.zeros(0)
    _mesh.write(filename, mesh.points, tets, point_data=mesh.point_data, cell_data=cell_data, **kwargs)


def register():
    import meshio

    meshio.register_format("gatun", [".gtn"], read, {"gatun": write})
