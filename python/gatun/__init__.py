"""gatun: compressed tetrahedral meshes (.gtn) from Python.

    import gatun
    mesh = gatun.read("blunt.gtn", ratio=0.9, fields=["density"])
    mesh.points, mesh.tets, mesh.point_data["density"]
    gatun.write("out.gtn", mesh.points, mesh.tets, point_data=mesh.point_data)
    gatun.info("out.gtn")["levels"]; gatun.validate("out.gtn")["ok"]

Importing gatun registers ".gtn" with meshio (when meshio is installed): meshio.read("x.gtn") and
meshio.write("x.gtn", mesh) work for tetrahedral meshes.
"""

from . import _gatun
from ._errors import (
    Error,
    InvalidDataError,
    IoError,
    NotOurFileError,
    UnsupportedError,
    UsageError,
    VersionTooNewError,
)
from ._mesh import Mesh, info, merge_tree_stats, plot_merge_tree, read, validate, write

__version__ = _gatun.__version__

__all__ = [
    "Error",
    "InvalidDataError",
    "IoError",
    "Mesh",
    "NotOurFileError",
    "UnsupportedError",
    "UsageError",
    "VersionTooNewError",
    "info",
    "merge_tree_stats",
    "plot_merge_tree",
    "read",
    "validate",
    "write",
]

try:
    import meshio as _meshio_module  # noqa: F401
except ImportError:  # meshio is optional
    pass
else:
    from . import _meshio

    _meshio.register()
