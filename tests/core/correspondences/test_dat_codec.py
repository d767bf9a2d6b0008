"""The original annotators' .dat ground-truth format: reading, writing, malformed files, the real files."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from correspondence_helpers import one_line_error

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    load_correspondences,
    load_dat,
    save_correspondences,
    save_dat,
)
from ursim_core.errors import FormatError
from ursim_core.evaluation import datasets

SAMPLE = """\
# /home/a/sketches/00.png ../../model_simple.png
# 0match set
# map1
228 302
# map2
166 308

# 1match set
# map1
414 442
# map2
297 407
339 393

# 2match set
# map1
# map2
12 13

# 3match set
# map1
# map2

"""


def _write(folder: Path, text: str, name: str = "gt.dat") -> Path:
    path = folder / name
    path.write_bytes(text.encode("utf-8"))
    return path


def test_sample_is_read_into_cliques(tmp_path):
    corr = load_dat(_write(tmp_path, SAMPLE))
    assert [clique.id for clique in corr.cliques] == [1, 2, 3, 4]
    assert corr.cliques[0].sketch_points == ((228, 302),)
    assert corr.cliques[0].metric_points == ((166, 308),)
    assert corr.cliques[1].metric_points == ((297, 407), (339, 393))
    assert corr.cliques[2].sketch_points == () and corr.cliques[2].metric_points == ((12, 13),)
    assert corr.cliques[3].is_empty
    assert all(clique.source == "manual" and clique.sketch_regions == () for clique in corr.cliques)


def test_header_paths_are_kept_as_written(tmp_path):
    corr = load_dat(_write(tmp_path, SAMPLE))
    assert corr.sketch.path == Path("/home/a/sketches/00.png")
    assert corr.metric.path == Path("../../model_simple.png")
    assert not corr.metric.path.is_absolute()
    assert corr.sketch.extra == {"dat_path": "/home/a/sketches/00.png"}
    assert corr.metric.extra == {"dat_path": "../../model_simple.png"}


def test_empty_sets_are_kept_unless_dropped(tmp_path):
    path = _write(tmp_path, SAMPLE)
    assert len(load_dat(path).cliques) == 4
    dropped = load_dat(path, drop_empty=True)
    # The one-sided set is annotation, not emptiness: it stays.
    assert [clique.metric_points for clique in dropped.cliques][-1] == ((12, 13),)
    assert [clique.id for clique in dropped.cliques] == [1, 2, 3]


def test_writing_gives_the_original_layout(tmp_path):
    corr = Correspondences(
        sketch=MapRef(path="/maps/s.png"),
        metric=MapRef(path="m.png"),
        cliques=(
            Clique(id=4, sketch_points=[(1, 2), (3, 4)], metric_points=[(5, 6)], sketch_regions=[9]),
            Clique(id=9),
        ),
    )
    target = tmp_path / "out.dat"
    save_dat(corr, target)
    assert target.read_bytes() == (
        b"# /maps/s.png m.png\n# 0match set\n# map1\n1 2\n3 4\n# map2\n5 6\n\n# 1match set\n# map1\n# map2\n\n"
    )


def test_round_trip_of_a_read_file_is_exact(tmp_path):
    source = _write(tmp_path, SAMPLE)
    corr = load_dat(source)
    target = tmp_path / "copy.dat"
    save_dat(corr, target)
    assert target.read_bytes() == source.read_bytes()
    assert load_dat(target) == corr


def test_round_trip_of_built_values_keeps_points_and_paths(tmp_path):
    corr = Correspondences(
        sketch=MapRef(path="sketch.png"),
        metric=MapRef(path="maps/metric.png"),
        cliques=(
            Clique(id=1, sketch_points=[(0, 0)], metric_points=[(7, 7), (8, 8)]),
            Clique(id=5, sketch_points=[(100, 2000)], metric_points=[]),
        ),
    )
    target = tmp_path / "x.dat"
    save_dat(corr, target)
    back = load_dat(target)
    assert back.sketch.path == corr.sketch.path and back.metric.path == corr.metric.path
    # .dat has no ids: they come back as 1, 2, ... in order.
    assert [(c.sketch_points, c.metric_points) for c in back.cliques] == [
        (c.sketch_points, c.metric_points) for c in corr.cliques
    ]
    assert [c.id for c in back.cliques] == [1, 2]


@pytest.mark.parametrize("name", ["my maps/sketch 1.png", "100%.png", "tab\there.png", "-"])
def test_awkward_header_paths_round_trip(tmp_path, name):
    corr = Correspondences(sketch=MapRef(path=name), metric=MapRef())
    target = tmp_path / "x.dat"
    save_dat(corr, target)
    header = target.read_text().splitlines()[0]
    assert len(header.split()) == 3  # "#", map1, map2
    back = load_dat(target)
    assert back.sketch.path == Path(name)
    assert back.metric.path is None


def test_a_renamed_path_wins_over_the_old_header_text(tmp_path):
    corr = load_dat(_write(tmp_path, SAMPLE))
    moved = Correspondences(sketch=MapRef(path="new.png", extra=corr.sketch.extra), metric=corr.metric)
    save_dat(moved, tmp_path / "moved.dat")
    assert (tmp_path / "moved.dat").read_text().splitlines()[0] == "# new.png ../../model_simple.png"


def test_windows_line_endings_and_extra_blank_lines_are_read(tmp_path):
    text = SAMPLE.replace("\n", "\r\n").replace("# 1match set", "\r\n\r\n# 1match set")
    corr = load_dat(_write(tmp_path, text))
    assert corr == load_dat(_write(tmp_path, SAMPLE, "unix.dat"))


def test_header_only_file_has_no_cliques(tmp_path):
    corr = load_dat(_write(tmp_path, "# a.png b.png\n"))
    assert corr.cliques == () and corr.sketch.path == Path("a.png")


MALFORMED = [
    ("empty", "", "empty file"),
    ("no-hash", "a.png b.png\n", "line 1: expected '# <map1 path> <map2 path>'"),
    ("one-path", "# a.png\n", "line 1"),
    ("three-paths", "# a b c\n", "line 1"),
    ("map1-before-set", "# a b\n# map1\n1 2\n", "line 2: '# map1' before the first '# Kmatch set'"),
    ("point-before-set", "# a b\n1 2\n", "line 2: point '1 2' before '# map1'"),
    ("point-before-map1", "# a b\n# 0match set\n3 4\n", "line 3: point '3 4' before"),
    ("map2-first", "# a b\n# 0match set\n# map2\n", "line 3: expected '# map1', got '# map2'"),
    ("map1-twice", "# a b\n# 0match set\n# map1\n# map1\n", "line 4: expected '# map2', got '# map1'"),
    ("map1-after-map2", "# a b\n# 0match set\n# map1\n# map2\n# map1\n", "line 5: '# map1' after '# map2'"),
    (
        "set-without-map2",
        "# a b\n# 0match set\n# map1\n1 2\n\n# 1match set\n",
        "line 6: the match set started on line 2 has no '# map2'",
    ),
    ("truncated", "# a b\n# 0match set\n# map1\n1 2\n", "line 5: the match set started on line 2 has no '# map2'"),
    ("empty-set-header", "# a b\n# 0match set\n", "has no '# map1' and '# map2'"),
    ("float", "# a b\n# 0match set\n# map1\n1.5 2\n# map2\n", "line 4: expected 'ROW COL'"),
    ("negative", "# a b\n# 0match set\n# map1\n-1 2\n# map2\n", "line 4"),
    ("three-numbers", "# a b\n# 0match set\n# map1\n1 2 3\n# map2\n", "line 4"),
    ("comment", "# a b\n# 0match set\n# hello\n", "line 3: expected 'ROW COL'"),
    ("bad-set-number", "# a b\n# xmatch set\n", "line 2"),
]


@pytest.mark.parametrize(("text", "problem"), [case[1:] for case in MALFORMED], ids=[case[0] for case in MALFORMED])
def test_malformed_files_name_the_line(tmp_path, text, problem):
    path = _write(tmp_path, text)
    with pytest.raises(FormatError) as caught:
        load_dat(path)
    assert caught.value.path == path
    assert problem in caught.value.problem


def test_binary_and_missing_files(tmp_path):
    path = tmp_path / "image.dat"
    path.write_bytes(b"# a b\n\xff\xfe\x00")
    with pytest.raises(FormatError, match="line 2: not text"):
        load_dat(path)
    with pytest.raises(FormatError, match="file not found"):
        load_dat(tmp_path / "absent.dat")


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    target = _write(tmp_path, SAMPLE)

    def failing_replace(source, destination):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError):
        save_dat(Correspondences(), target)
    assert target.read_text() == SAMPLE
    assert [path.name for path in tmp_path.iterdir()] == ["gt.dat"]


# --------------------------------------------------------------------------- the published files


def _real_dat_files() -> list[Path]:
    root = datasets.dataset_root()
    if root is None:
        pytest.skip(datasets.MISSING_REASON)
    files = sorted((root / "ursim_kth_sketches" / "gt_correspondences").glob("*/*.dat"))
    files += sorted((root / "ursim_halmstad_robot_maps" / "E5" / "GT").glob("*/*.dat"))
    if not files:
        pytest.skip(f"no .dat files under {root}")
    return files


@pytest.mark.dataset
def test_every_real_file_round_trips_byte_for_byte(tmp_path):
    files = _real_dat_files()
    assert len(files) >= 40
    for source in files:
        corr = load_dat(source)
        target = tmp_path / source.name
        save_dat(corr, target)
        assert target.read_bytes() == source.read_bytes(), source
        assert load_dat(target) == corr, source


@pytest.mark.dataset
def test_real_files_match_the_dataset_description():
    root = datasets.dataset_root()
    files = _real_dat_files()
    sketch_gt = [path for path in files if "gt_correspondences" in str(path) and path.name[3].isdigit()]
    assert len(sketch_gt) == 36
    for path in sketch_gt:
        corr = load_dat(path)
        non_empty = [clique for clique in corr.cliques if not clique.is_empty]
        # README: 3-8 non-empty sets per file; map1 is the sketch, map2 the model.
        assert 3 <= len(non_empty) <= 8, path
        assert corr.metric.path.name == "model_simple.png"
        assert corr.sketch.path.name == path.name[3:5] + ".png"
        if "malcolm" in path.parts:
            assert corr.cliques[-1].is_empty, path  # Malcolm's files all end with an empty set
            assert len(load_dat(path, drop_empty=True).cliques) == len(non_empty)
    # README: vasiliki/gt_14 has one set with points on only one side.
    one_sided = [
        (path.parent.name, path.name, clique.id)
        for path in sketch_gt
        for clique in load_dat(path).cliques
        if bool(clique.sketch_points) != bool(clique.metric_points)
    ]
    assert one_sided == [("vasiliki", "gt_14_model_simple.dat", 5)]

    first = load_dat(root / "ursim_kth_sketches" / "gt_correspondences" / "malcolm" / "gt_00_model_simple.dat")
    assert first.cliques[0].sketch_points == ((228, 302),)
    assert first.cliques[0].metric_points == ((166, 308),)
    assert first.cliques[1].metric_points == ((297, 407), (339, 393))


# =========================================================================== issue 12
# Defects the reliability pass found in .dat files, reproduced (items by number).

NOW = "2024-05-01T12:00:00Z"


# --------------------------------------------------------------------------- issue 12, item 4: the .dat header


SAMPLE_DAT = """\
# /home/a/sketches/00.png ../../model_simple.png
# 0match set
# map1
228 302
# map2
166 308

"""


def test_dat_header_survives_dat_json_dat(tmp_path, monkeypatch):
    source = tmp_path / "in" / "gt.dat"
    source.parent.mkdir()
    source.write_text(SAMPLE_DAT, encoding="utf-8")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    middle = tmp_path / "out" / "gt.json"
    middle.parent.mkdir()
    save_correspondences(load_dat(source), middle, now=NOW)
    monkeypatch.chdir(tmp_path)
    again = tmp_path / "gt.dat"
    save_dat(load_correspondences(middle), again)
    assert again.read_text(encoding="utf-8") == SAMPLE_DAT


def test_dat_header_is_rewritten_when_the_map_really_changed(tmp_path):
    source = tmp_path / "gt.dat"
    source.write_text(SAMPLE_DAT, encoding="utf-8")
    corr = load_dat(source)
    moved = Correspondences(MapRef(path="/data/other.png", extra=corr.sketch.extra), corr.metric, cliques=corr.cliques)
    target = tmp_path / "out.dat"
    save_dat(moved, target)
    assert target.read_text(encoding="utf-8").splitlines()[0] == "# /data/other.png ../../model_simple.png"


@pytest.mark.dataset
def test_every_published_header_survives_dat_json_dat(tmp_path, monkeypatch):
    root = datasets.dataset_root()
    if root is None:
        pytest.skip(datasets.MISSING_REASON)
    files = sorted(root.glob("**/*.dat"))
    assert len(files) == 91
    monkeypatch.chdir(tmp_path)
    for index, source in enumerate(files):
        middle = tmp_path / f"{index}.json"
        save_correspondences(load_dat(source), middle, now=NOW)
        target = tmp_path / f"{index}.dat"
        save_dat(load_correspondences(middle), target)
        assert target.read_bytes() == source.read_bytes(), source


# --------------------------------------------------------------------------- issue 12, item 10: numbers, and a NUL


def test_huge_integer_in_a_dat_file_is_a_format_error(tmp_path):
    path = tmp_path / "gt.dat"
    path.write_text("# a.png b.png\n# 0match set\n# map1\n" + "9" * 5000 + " 1\n# map2\n", encoding="utf-8")
    with pytest.raises(FormatError, match="line 4") as caught:
        load_dat(path)
    one_line_error(path, caught.value)


def test_nul_in_a_dat_header_is_a_format_error(tmp_path):
    path = tmp_path / "gt.dat"
    path.write_text("# a%00.png b.png\n", encoding="utf-8")
    with pytest.raises(FormatError, match="line 1"):
        load_dat(path)
