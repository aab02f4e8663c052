"""gatun: compressed tetrahedral meshes (.gtn) from Python.

    import gatun
    mesh = gatun.read("blunt.gtn", ratio=0.9, fields=["density"])
    mesh.points, mesh.tets, mesh.point_data["density"]
    gatun.write("out.gtn", mesh.points, mesh.tets, point_data=mesh.point_data)
    gatun.info("out.gtn")["levels"]; gatun.validate("out.gtn")["ok"]

Importing gatun registers ".gtn" with meshio (when meshio is installed; at meshio's own import if it
comes later, so that gatun alone does not import it): meshio.read("x.gtn") and meshio.write("x.gtn",
mesh) work for tetrahedral meshes.
"""

from . import _gatun
from ._errors import (
    DamagedChunkWarning,
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
    "DamagedChunkWarning",
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

def _register_with_meshio():
    """Registers .gtn with meshio now if meshio is imported, else when it is: meshio's import (about
    as long as numpy's) is not paid by a program that never uses it."""
    import sys

    if "meshio" in sys.modules:
        from . import _meshio

        _meshio.register()
        return
    import importlib.abc
    import importlib.util

    class _Loader(importlib.abc.Loader):
        def __init__(self, loader):
            self._loader = loader

        def create_module(self, spec):
            return self._loader.create_module(spec)

        def exec_module(self, module):
            self._loader.exec_module(module)
            from . import _meshio

            _meshio.register()

    class _Finder(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name != "meshio":
                return None
            sys.meta_path.remove(self)  # once; the search below goes to the other finders
            spec = importlib.util.find_spec(name)
            if spec is not None and spec.loader is not None and hasattr(spec.loader, "exec_module"):
                spec.loader = _Loader(spec.loader)
            return spec

    sys.meta_path.insert(0, _Finder())


_register_with_meshio()
