"""`import gatun` registers .gtn with meshio: meshio -> .gtn -> meshio keeps the mesh (up to renumbering)."""

import subprocess
import sys
import warnings

import meshio
import numpy as np
import pytest

import gatun


def canonical(points, tets, point_data, cell_data):
    """The mesh in an order of its own: points sorted by coordinates then values, tetrahedra as their
    corners' coordinates (each tetrahedron's corners sorted, then the tetrahedra), so that coincident
    points (blunt fin has some) compare equal whichever of them a tetrahedron names."""
    points = np.asarray(points)
    columns = [points[:, i] for i in range(3)]
    for v in point_data.values():
        a = np.asarray(v)
        columns += [a.reshape(len(a), -1)[:, j] for j in range(a.reshape(len(a), -1).shape[1])]
    order = np.lexsort(columns[::-1])
    corners = points[np.asarray(tets, dtype=np.int64)]  # (n, 4, 3)
    inner = np.lexsort((corners[:, :, 2], corners[:, :, 1], corners[:, :, 0]), axis=-1)
    corners = np.take_along_axis(corners, inner[:, :, None], axis=1).reshape(len(corners), 12)
    torder = np.lexsort(corners.T[::-1])
    return (points[order], corners[torder], {k: np.asarray(v)[order] for k, v in point_data.items()},
            {k: np.asarray(v)[torder] for k, v in cell_data.items()})


def assert_same(a, b):
    for x, y in zip(a[:2], b[:2]):
        assert np.array_equal(x, y)
    for da, db in zip(a[2:], b[2:]):
        assert sorted(da) == sorted(db)
        for k in da:
            assert da[k].dtype == db[k].dtype and np.array_equal(da[k], db[k], equal_nan=True)


def test_registered():
    assert "gatun" in meshio._helpers.extension_to_filetypes[".gtn"]


def test_meshio_imported_after_gatun(converted):
    # import gatun does not import meshio (its import costs as much as numpy's); meshio imported
    # afterwards knows .gtn, and reads the same mesh as gatun.read.
    code = (
        "import sys, gatun\n"
        "assert 'meshio' not in sys.modules\n"
        "import meshio\n"
        f"m = meshio.read({str(converted['bluntfin'])!r})\n"
        f"g = gatun.read({str(converted['bluntfin'])!r})\n"
        "assert (m.points == g.points).all() and (m.cells[0].data == g.tets).all()\n"
        "assert sorted(m.point_data) == sorted(g.point_data)\n"
        "print(len(m.cells[0].data))\n"
    )
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == [str(len(gatun.read(converted["bluntfin"]).tets))]


def test_round_trip_medit_bunny(data_dir, tmp_path):
    source = meshio.read(data_dir / "medit" / "bunny.mesh")
    tetra = [b for b in source.cells if b.type == "tetra"]
    mesh = meshio.Mesh(source.points, tetra, point_data=source.point_data,
                       cell_data={k: [v[i] for i, b in enumerate(source.cells) if b.type == "tetra"]
                                  for k, v in source.cell_data.items()})
    path = tmp_path / "bunny.gtn"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # orientation fixes, if any, are checked below
        meshio.write(path, mesh)
    back = meshio.read(path)
    assert [b.type for b in back.cells] == ["tetra"]
    assert len(back.points) == len(mesh.points) and len(back.cells[0].data) == len(mesh.cells[0].data)
    assert back.points.dtype == mesh.points.dtype
    # Orientation may have been normalised: compare tetrahedra as point sets.
    a = canonical(mesh.points, mesh.cells[0].data, mesh.point_data, {k: v[0] for k, v in mesh.cell_data.items()})
    b = canonical(back.points, back.cells[0].data, back.point_data, {k: v[0] for k, v in back.cell_data.items()})
    assert_same(a, b)


def test_round_trip_blunt_fin_from_gtn(converted, tmp_path):
    # meshio reads a gtn file written by `gtn convert`, writes it as .gtn, reads it back.
    first = meshio.read(converted["bluntfin"])
    path = tmp_path / "again.gtn"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meshio.write(path, first)
    second = meshio.read(path)
    assert_same(canonical(first.points, first.cells[0].data, first.point_data, {}),
                canonical(second.points, second.cells[0].data, second.point_data, {}))


def test_other_cells_are_refused(tmp_path):
    points = np.eye(4, 3)
    mesh = meshio.Mesh(points, [("tetra", [[0, 1, 2, 3]]), ("triangle", [[0, 1, 2], [1, 2, 3]])])
    path = tmp_path / "mixed.gtn"
    with pytest.raises(gatun.UsageError, match=r"tetrahedra only; the mesh has other cells \(2 triangle\)"):
        meshio.write(path, mesh)
    assert not path.exists()


def test_meshio_write_takes_gatun_write_options(converted, tmp_path):
    # meshio.write passes its keyword arguments on to gatun.write.
    source = gatun.read(converted["bluntfin"], level=len(gatun.info(converted["bluntfin"])["levels"]) - 1)
    mesh = meshio.Mesh(source.points, [("tetra", source.tets)], point_data=source.point_data)
    path = tmp_path / "one-level.gtn"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        meshio.write(path, mesh, levels=0, merge_tree=False)
    info = gatun.info(path, merge_tree=True)
    assert len(info["levels"]) == 1 and info["merge_tree"] is None
    assert info["levels"][0]["tets"] == len(source.tets)
    back = meshio.read(path)
    assert back.points.dtype == np.float32
    assert np.array_equal(np.sort(back.point_data["density"]), np.sort(source.point_data["density"]))
