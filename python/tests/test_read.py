"""gatun.read against `gtn export` (the same decode, bit for bit) on the real datasets."""

import warnings

import meshio
import numpy as np
import pytest

import gatun


def exported(gtn, path, tmp_path, *args):
    vtu = tmp_path / "export.vtu"
    gtn.run("export", path, "-o", vtu, *args)
    return meshio.read(vtu)


def assert_same_array(a, b):
    a, b = np.asarray(a), np.asarray(b)
    assert a.dtype == b.dtype
    assert a.shape == b.shape
    # Bit for bit: compare the bytes, so that NaN payloads and signed zeros count too.
    assert np.ascontiguousarray(a).tobytes() == np.ascontiguousarray(b).tobytes()


def one_column(ref, values):
    """meshio gives a 1-component VTK array as (n, 1); gatun gives (n,)."""
    ref = np.asarray(ref)
    return ref[:, 0] if values.ndim == 1 and ref.ndim == 2 and ref.shape[1] == 1 else ref


def assert_matches_export(mesh, ref):
    assert_same_array(mesh.points, ref.points)
    assert [b.type for b in ref.cells] == ["tetra"]
    assert_same_array(mesh.tets.astype(np.int64), ref.cells[0].data.astype(np.int64))
    assert sorted(mesh.point_data) == sorted(ref.point_data)
    for name, values in mesh.point_data.items():
        assert_same_array(values, one_column(ref.point_data[name], values))
    assert sorted(mesh.cell_data) == sorted(ref.cell_data)
    for name, values in mesh.cell_data.items():
        assert_same_array(values, one_column(ref.cell_data[name][0], values))


@pytest.mark.parametrize("name", ["bunny", "bluntfin"])
def test_level0_equals_export(gtn, converted, tmp_path, name):
    mesh = gatun.read(converted[name])
    info = gtn.json("info", "--json", converted[name])
    assert len(mesh.points) == info["points"] and len(mesh.tets) == info["tets"]
    assert mesh.level == 0 and mesh.merges == 0 and mesh.ratio == 0
    assert mesh.metadata == info["metadata"]
    assert_matches_export(mesh, exported(gtn, converted[name], tmp_path))


def test_stored_precision(converted):
    blunt = gatun.read(converted["bluntfin"])
    assert blunt.points.dtype == np.float32  # PLOT3D single precision stays single
    assert blunt.point_data["momentum"].shape == (len(blunt.points), 3)
    assert blunt.point_data["density"].dtype == np.float32
    assert blunt.tets.dtype == np.uint32 and blunt.tets.shape == (224874, 4)


def test_arrays_are_handed_over_without_copy(converted):
    mesh = gatun.read(converted["bunny"])
    # The decoder's buffers, owned by a capsule: numpy did not allocate (copy) them.
    for a in [mesh.points, mesh.tets, *mesh.point_data.values(), *mesh.cell_data.values()]:
        assert not a.flags.owndata
        assert type(a.base).__name__ == "PyCapsule"


@pytest.mark.parametrize("level", [1, 2])
def test_stored_level_equals_export(gtn, converted, tmp_path, level):
    mesh = gatun.read(converted["bluntfin"], level=level)
    assert mesh.level == level
    assert_matches_export(mesh, exported(gtn, converted["bluntfin"], tmp_path, "--level", level))


@pytest.mark.parametrize("ratio", [0.3, 0.8, 1.0])
def test_ratio_equals_export(gtn, converted, tmp_path, ratio):
    mesh = gatun.read(converted["bluntfin"], ratio=ratio)
    assert_matches_export(mesh, exported(gtn, converted["bluntfin"], tmp_path, "--ratio", ratio))
    info = gatun.info(converted["bluntfin"])
    assert mesh.level == max(l["level"] for l in info["levels"] if l["ratio"] <= ratio)
    assert mesh.ratio == pytest.approx(ratio, abs=1.0 / info["points"] + 1e-3)


def test_fields_selection_equals_export(gtn, converted, tmp_path):
    mesh = gatun.read(converted["bluntfin"], fields=["momentum"], threads=2)
    assert list(mesh.point_data) == ["momentum"]
    assert_matches_export(mesh, exported(gtn, converted["bluntfin"], tmp_path, "--fields", "momentum"))


@pytest.mark.parametrize("how", [{}, {"level": 2}, {"ratio": 0.6, "fields": ["density"]}])
def test_box_keeps_the_tetrahedra_meeting_it(converted, how):
    # The box applies to whatever level, ratio and fields the read decodes.
    full = gatun.read(converted["bluntfin"], **how)
    box = np.array([0.0, 1.0, 0.5, 3.0, 3.0, 2.0])
    part = gatun.read(converted["bluntfin"], box=box, **how)
    assert (part.level, part.merges, part.ratio) == (full.level, full.merges, full.ratio)
    assert sorted(part.point_data) == sorted(full.point_data)
    lo, hi = box[:3], box[3:]
    assert 0 < len(part.tets) < len(full.tets)
    # Points are those the kept tetrahedra use, each with its values.
    assert np.array_equal(np.unique(part.tets), np.arange(len(part.points)))
    corners = part.points[part.tets]  # (m, 4, 3)
    assert np.all(corners.max(axis=1) >= lo) and np.all(corners.min(axis=1) <= hi)
    # Every tetrahedron with a corner inside the box is kept; none whose bounding box misses it.
    def keys(points, tets):
        return {tuple(sorted(map(tuple, points[t].tolist()))) for t in tets}
    fc = full.points[full.tets]
    inside = np.any(np.all((fc >= lo) & (fc <= hi), axis=2), axis=1)
    overlaps = np.all((fc.max(axis=1) >= lo) & (fc.min(axis=1) <= hi), axis=1)
    kept = keys(part.points, part.tets)
    assert keys(full.points, full.tets[inside]) <= kept
    assert kept <= keys(full.points, full.tets[overlaps])
    # Point values follow their points.
    where = {tuple(p): i for i, p in enumerate(full.points.tolist())}
    index = np.array([where[tuple(p)] for p in part.points.tolist()])
    for name in full.point_data:
        assert np.array_equal(part.point_data[name], full.point_data[name][index])


def test_box_is_exact_not_bounding_boxes(tmp_path):
    points = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 1],  # beyond the plane x+y+z=1
                       [-1, -1, -1], [2, -1, -1], [-1, 2, -1], [-1, -1, 2]], dtype=np.float64)  # around the box
    tets = np.array([[0, 1, 2, 3], [4, 5, 6, 7]])
    path = tmp_path / "two.gtn"
    gatun.write(path, points, tets, cell_data={"id": np.array([10, 20], dtype=np.int32)}, levels=0, merge_tree=False)
    part = gatun.read(path, box=(0, 0, 0, 0.2, 0.2, 0.2))
    # The first tetrahedron's bounding box meets the box, the tetrahedron does not; the second holds it.
    assert part.cell_data["id"].tolist() == [20]
    assert len(part.points) == 4


def test_bad_arguments_and_files(gtn, converted, data_dir, tmp_path):
    with pytest.raises(gatun.UsageError, match="level and ratio exclude each other"):
        gatun.read(converted["bunny"], level=1, ratio=0.5)
    with pytest.raises(ValueError, match=r"level 9: the file holds \d+ level\(s\)"):
        gatun.read(converted["bunny"], level=9)
    with pytest.raises(gatun.UsageError, match="no field named 'nope'"):
        gatun.read(converted["bunny"], fields=["nope"])
    with pytest.raises(gatun.UsageError, match="level -1 is negative"):
        gatun.read(converted["bunny"], level=-1)
    with pytest.raises(gatun.UsageError, match="box: its minimum must not exceed its maximum"):
        gatun.read(converted["bunny"], box=(1, 1, 1, 0, 0, 0))
    with pytest.raises(gatun.UsageError, match=r"box has 5 values, not 6 \(xmin, ymin, zmin, xmax, ymax, zmax\)"):
        gatun.read(converted["bunny"], box=(0, 0, 0, 1, 1))
    with pytest.raises(gatun.UsageError, match="threads 0 must be 1 or more"):
        gatun.read(converted["bunny"], threads=0)
    with pytest.raises(gatun.UsageError, match="bunny.mesh: a Medit file, not .gtn: gatun.read reads .gtn files"):
        gatun.read(data_dir / "medit" / "bunny.mesh")
    # A missing file and a directory: the message `gtn export` prints.
    for missing in (tmp_path / "missing.gtn", tmp_path):
        with pytest.raises(OSError) as e:
            gatun.read(missing)
        assert isinstance(e.value, gatun.IoError) and isinstance(e.value, gatun.Error)
        r = gtn.run("export", missing, "-o", tmp_path / "out.vtu", check=False)
        assert r.returncode == 3 and r.stderr.strip() == "gtn: error: " + str(e.value)
    # A damaged file: the exception carries the message gtn prints.
    data = bytearray(converted["bunny"].read_bytes())
    info = gatun.info(converted["bunny"])
    head = sum(s["bytes"] for s in info["sections"] if s["name"] in ("prefix", "header"))
    data[head + info["levels"][0]["bytes"] // 2] ^= 0xFF  # inside level 0
    bad = tmp_path / "bad.gtn"
    bad.write_bytes(bytes(data))
    r = gtn.run("export", bad, "-o", tmp_path / "bad.vtu", check=False)
    assert r.returncode == 1
    with pytest.raises(gatun.InvalidDataError) as e:
        gatun.read(bad)
    assert r.stderr.strip() == "gtn: error: " + str(e.value)
    assert isinstance(e.value, ValueError) and isinstance(e.value, RuntimeError)


def test_ratio_counts_the_points_tetrahedra_use(tmp_path):
    # A grid of cubes in six tetrahedra each, with the midpoint of every edge as an unreferenced
    # point (a quadratic mesh's mid-edge nodes): read at a ratio reports that ratio, counted over the
    # corner points as the stored levels count it (it counted every point).
    n = 6
    ids = np.arange((n + 1) ** 3).reshape(n + 1, n + 1, n + 1)
    grid = np.stack(np.meshgrid(*[np.arange(n + 1.0)] * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    kuhn = [(0, 1, 3, 7), (0, 3, 2, 7), (0, 2, 6, 7), (0, 6, 4, 7), (0, 4, 5, 7), (0, 5, 1, 7)]
    tets = []
    for i in range(n):
        for j in range(n):
            for k in range(n):
                c = [ids[i + (b & 1), j + (b >> 1 & 1), k + (b >> 2 & 1)] for b in range(8)]
                tets += [[c[a] for a in t] for t in kuhn]
    tets = np.array(tets, dtype=np.int64)
    edges = {tuple(sorted((t[a], t[b]))) for t in tets.tolist() for a in range(4) for b in range(a + 1, 4)}
    mids = np.array([(grid[a] + grid[b]) / 2 for a, b in sorted(edges)])
    points = np.vstack([grid, mids])
    path = tmp_path / "quadratic.gtn"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gatun.write(path, points, tets, levels=2)
    mesh = gatun.read(path, ratio=0.3)
    assert mesh.ratio == pytest.approx(0.3, abs=2.0 / len(grid))


def test_threads_bound_the_call_and_change_nothing(converted):
    # A level decodes on one thread; threads bounds TBB for the call and leaves the result alone.
    one = gatun.read(converted["bluntfin"], threads=1, box=(0.0, 1.0, 0.5, 3.0, 3.0, 2.0))
    many = gatun.read(converted["bluntfin"], threads=4, box=(0.0, 1.0, 0.5, 3.0, 3.0, 2.0))
    assert_same_array(one.points, many.points)
    assert_same_array(one.tets, many.tets)
    assert sorted(one.point_data) == sorted(many.point_data)
    for name in one.point_data:
        assert_same_array(one.point_data[name], many.point_data[name])


@pytest.mark.parametrize("level", [0, 2])
def test_library_decode_counts(converted, level):
    # gatun._gatun.decode, bench/python's baseline, decodes the same level as gatun.read.
    from gatun import _gatun

    mesh = gatun.read(converted["bluntfin"], level=level)
    assert _gatun.decode(str(converted["bluntfin"]), level) == (len(mesh.points), len(mesh.tets))
    with pytest.raises(gatun.UsageError, match="level 9 does not exist"):
        _gatun.decode(str(converted["bluntfin"]), 9)


def test_damage_elsewhere_is_a_warning_as_in_gtn_export(gtn, converted, tmp_path):
    # A byte flipped inside level 2: reading level 0 warns as `gtn export` does and decodes; reading
    # level 2 fails with gtn's error.
    path = converted["bluntfin"]
    info = gatun.info(path)
    head = sum(s["bytes"] for s in info["sections"] if s["name"] in ("prefix", "header"))
    start = head + sum(l["bytes"] for l in info["levels"][:2])
    data = bytearray(path.read_bytes())
    data[start + info["levels"][2]["bytes"] // 2] ^= 0x5A
    bad = tmp_path / "damaged.gtn"
    bad.write_bytes(bytes(data))
    r = gtn.run("export", bad, "-o", tmp_path / "level0.vtu")
    said = [line[len("gtn: warning: "):] for line in r.stderr.splitlines() if line.startswith("gtn: warning: ")]
    assert len(said) == 1 and "checksum mismatch" in said[0]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        mesh = gatun.read(bad)
    assert [str(w.message) for w in caught] == said
    assert all(w.category is gatun.DamagedChunkWarning for w in caught)
    assert_matches_export(mesh, meshio.read(tmp_path / "level0.vtu"))
    r = gtn.run("export", bad, "--level", 2, "-o", tmp_path / "level2.vtu", check=False)
    assert r.returncode == 1
    with pytest.raises(gatun.InvalidDataError) as e:
        gatun.read(bad, level=2)
    assert r.stderr.strip() == "gtn: error: " + str(e.value)
