"""A .dat file is saved only when it reads back (ursim_core.correspondences.dat_codec): coordinates of
more than 18 digits are refused naming the file and the clique; a byte-order mark is read."""

from __future__ import annotations

import pytest

from ursim_core.correspondences import Clique, Correspondences, MapRef, load_dat, save_dat
from ursim_core.errors import FormatError


def _pair(*cliques):
    return Correspondences(MapRef(path="a.png"), MapRef(path="b.png"), cliques=cliques)


def test_a_coordinate_the_reader_refuses_is_not_saved(tmp_path):
    huge = 10**20
    corr = _pair(
        Clique(id=1, sketch_points=[(1, 2)], metric_points=[(3, 4)]),
        Clique(id=7, sketch_points=[(1, 2)], metric_points=[(5, 6), (huge, 4)]),
    )
    target = tmp_path / "x.dat"
    with pytest.raises(FormatError, match="more than 18 digits") as caught:
        save_dat(corr, target)
    message = str(caught.value)
    assert message.startswith(f"{target}: ") and "clique 7" in message
    assert caught.value.field == "cliques[1].metric_points[1]"
    assert not target.exists()


def test_the_largest_coordinates_the_reader_takes_round_trip(tmp_path):
    largest = 10**18 - 1
    corr = _pair(Clique(id=1, sketch_points=[(largest, 0)], metric_points=[(3, largest)]))
    save_dat(corr, tmp_path / "x.dat")
    again = load_dat(tmp_path / "x.dat")
    assert again.cliques[0].sketch_points == ((largest, 0),)
    assert again.cliques[0].metric_points == ((3, largest),)


def test_a_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "bom.dat"
    path.write_bytes(b"\xef\xbb\xbf# a.png b.png\n# 0match set\n# map1\n1 2\n# map2\n3 4\n")
    corr = load_dat(path)
    assert corr.sketch.path.name == "a.png" and corr.cliques[0].metric_points == ((3, 4),)
