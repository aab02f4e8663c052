"""Reads by piece and by box of a level stored as many pieces (`gtn convert --piece-tets 4096` of blunt
fin): the pieces' union is the whole level, a box read decodes exactly the pieces meeting the box."""

import numpy as np
import pytest

import gatun


@pytest.fixture(scope="session")
def pieced(gtn, data_dir, tmp_path_factory):
    path = tmp_path_factory.mktemp("pieced") / "bluntfin-pieces.gtn"
    gtn.run("convert", data_dir / "plot3d" / "bluntfinxyz.bin", data_dir / "plot3d" / "bluntfinq.bin",
            "--piece-tets", 4096, "--levels", 1, "-o", path)
    return path


def sorted_tets(tets):
    """The tetrahedra as rows of point numbers, sorted lexicographically (vertex order kept)."""
    tets = np.asarray(tets, dtype=np.int64)
    return tets[np.lexsort(tets.T[::-1])]


def piece_table(path, level=0):
    return gatun.info(path)["levels"][level]["pieces"]


def meets(piece, lo, hi):
    return all(piece["bbox"]["min"][k] <= hi[k] and lo[k] <= piece["bbox"]["max"][k] for k in range(3))


def test_the_info_shows_the_piece_table(pieced):
    level = gatun.info(pieced)["levels"][0]
    assert level["piece_count"] == len(level["pieces"]) > 1
    assert sum(p["tets"] for p in level["pieces"]) == level["tets"]
    assert all(p["tets"] <= 4096 for p in level["pieces"])


@pytest.mark.parametrize("level", [0, 1])
def test_the_union_of_all_pieces_is_the_whole_level(pieced, level):
    whole = gatun.read(pieced, level=level)
    table = piece_table(pieced, level)
    assert whole.pieces == list(range(len(table)))
    assert whole.point_ids is None and whole.tet_ids is None
    point_ids, tet_ids, tets = [], [], []
    for p in range(len(table)):
        part = gatun.read(pieced, level=level, pieces=[p])
        assert part.pieces == [p]
        assert len(part.tets) == table[p]["tets"]
        assert part.point_ids.dtype == np.uint32 and part.tet_ids.dtype == np.uint64
        # Each piece's points and values are the whole read's points of the same numbers.
        assert np.array_equal(part.points, whole.points[part.point_ids])
        for name, values in part.point_data.items():
            assert np.array_equal(values, whole.point_data[name][part.point_ids])
        assert np.array_equal(part.point_ids[part.tets], whole.tets[part.tet_ids])
        point_ids.append(part.point_ids)
        tet_ids.append(part.tet_ids)
        tets.append(part.point_ids[part.tets])
    # Every tetrahedron in exactly one piece, every point in at least one (seam points in several).
    assert np.array_equal(np.sort(np.concatenate(tet_ids)), np.arange(len(whole.tets)))
    assert np.array_equal(np.unique(np.concatenate(point_ids)), np.arange(len(whole.points)))
    assert sum(len(ids) for ids in point_ids) > len(whole.points)
    assert np.array_equal(sorted_tets(np.concatenate(tets)), sorted_tets(whole.tets))


def test_a_run_of_pieces_is_stitched(pieced):
    table = piece_table(pieced)
    run = list(range(2, 6))
    part = gatun.read(pieced, pieces=run[::-1] + [3])  # any order, repeats once
    assert part.pieces == run
    assert len(part.tets) == sum(table[p]["tets"] for p in run)
    # Seam points between the run's pieces are one point each.
    assert len(np.unique(part.point_ids)) == len(part.point_ids)
    whole = gatun.read(pieced)
    assert np.array_equal(sorted_tets(part.point_ids[part.tets]), sorted_tets(whole.tets[np.sort(part.tet_ids)]))


@pytest.mark.parametrize("fields", [None, ["density"]])
def test_a_box_read_decodes_the_pieces_meeting_the_box(pieced, fields):
    box = np.array([0.0, 1.0, 0.5, 3.0, 3.0, 2.0])
    lo, hi = box[:3], box[3:]
    table = piece_table(pieced)
    expected = [p for p in range(len(table)) if meets(table[p], lo, hi)]
    assert 0 < len(expected) < len(table)
    part = gatun.read(pieced, box=box, fields=fields)
    assert part.pieces == expected
    # The box read is the tetrahedra of those pieces that meet the box: the union of the box reads of
    # each piece alone, and the whole level's tetrahedra of the same numbers.
    one_by_one = [gatun.read(pieced, box=box, pieces=[p], fields=fields) for p in expected]
    assert np.array_equal(np.sort(part.tet_ids), np.sort(np.concatenate([o.tet_ids for o in one_by_one])))
    whole = gatun.read(pieced, fields=fields)
    assert 0 < len(part.tets) < len(whole.tets)
    assert np.array_equal(part.point_ids[part.tets], whole.tets[part.tet_ids])
    assert np.array_equal(part.points, whole.points[part.point_ids])
    assert sorted(part.point_data) == sorted(whole.point_data)
    for name, values in part.cell_data.items():
        assert np.array_equal(values, whole.cell_data[name][part.tet_ids])
    # Every kept tetrahedron comes from a decoded piece: the pieces' own reads hold it.
    held = np.concatenate([gatun.read(pieced, pieces=[p]).tet_ids for p in expected])
    assert np.isin(part.tet_ids, held).all()


def test_a_box_and_pieces_meet(pieced):
    box = (0.0, 1.0, 0.5, 3.0, 3.0, 2.0)
    table = piece_table(pieced)
    in_box = [p for p in range(len(table)) if meets(table[p], box[:3], box[3:])]
    others = [p for p in range(len(table)) if p not in in_box]
    part = gatun.read(pieced, box=box, pieces=others[:3])
    assert part.pieces == [] and len(part.tets) == 0 and len(part.points) == 0
    assert sorted(part.point_data) == sorted(gatun.read(pieced, pieces=[0]).point_data)
    part = gatun.read(pieced, box=box, pieces=in_box[:1] + others[:1])
    assert part.pieces == in_box[:1]


def test_bad_pieces_are_usage_errors(pieced):
    n = len(piece_table(pieced))
    with pytest.raises(gatun.UsageError, match=rf"level 0: pieces: no piece {n} \(the level has {n} piece\(s\), 0 to {n - 1}\)"):
        gatun.read(pieced, pieces=[0, n])
    with pytest.raises(gatun.UsageError, match="pieces: no piece -1"):
        gatun.read(pieced, pieces=[-1])
    with pytest.raises(gatun.UsageError, match="pieces and ratio exclude each other"):
        gatun.read(pieced, ratio=0.5, pieces=[0])
