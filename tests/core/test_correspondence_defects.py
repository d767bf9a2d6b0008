"""Issue 12, correspondence files: each defect the reliability pass found, reproduced.

Items: 1 (non-UTF-8 file names), 2 (inf / lone surrogates), 3 (changed on disk, saving onto a
map), 4 (.dat header kept through JSON), 9 (deep nesting), 10 (numbers that crash),
14 (sha256 mismatch, region ids that disagree), 16 is a benchmark (``ursim bench files``).
"""

from __future__ import annotations

import json
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    assign_regions,
    load_correspondences,
    load_dat,
    save_correspondences,
    save_dat,
)
from ursim_core.errors import (
    FileChangedError,
    FormatError,
    MapChangedWarning,
    RegionsRecomputedWarning,
    SaveRefusedError,
    UrsimError,
)
from ursim_core.evaluation import datasets
from ursim_core.io import map_from_array

NOW = "2024-05-01T12:00:00Z"
posix_only = pytest.mark.skipif(sys.platform == "win32", reason="POSIX file names are bytes")


def _document(**changes) -> dict:
    document = {
        "format": "ursim-correspondences",
        "version": 1,
        "maps": {"sketch": {"path": "a.png"}, "metric": {"path": "b.png"}},
        "cliques": [{"id": 1, "sketch_points": [[1, 2]], "metric_points": [[3, 4]]}],
    }
    document.update(changes)
    return document


def _write_json_text(folder: Path, text: str, name: str = "pair.json") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path


def _one_line_error(path: Path, error: UrsimError) -> str:
    message = str(error)
    assert "\n" not in message
    assert str(path) in message or path.name in message
    return message


# --------------------------------------------------------------------------- 1: file names


@posix_only
def test_non_utf8_map_name_round_trips_through_json_and_dat(tmp_path):
    odd = Path(os.fsdecode(b"plan_\xe9tage.png"))  # a Latin-1 name: a lone surrogate in Python
    corr = Correspondences(
        MapRef(path=tmp_path / odd),
        MapRef(path=tmp_path / "model.png"),
        cliques=(Clique(id=1, sketch_points=[(1, 2)]),),
    )
    target = tmp_path / "pair.json"
    save_correspondences(corr, target, now=NOW)
    back = load_correspondences(target)
    assert os.fsencode(back.sketch.path) == os.fsencode(tmp_path / odd)
    assert target.read_bytes().decode("utf-8")  # the file itself stays valid UTF-8

    dat = tmp_path / "gt.dat"
    save_dat(back, dat)
    dat.read_bytes().decode("utf-8")
    assert os.fsencode(load_dat(dat).sketch.path) == os.fsencode(tmp_path / odd)


def test_nul_in_a_map_path_is_a_format_error(tmp_path):
    document = _document()
    document["maps"]["sketch"]["path"] = "a\u0000b.png"
    path = _write_json_text(tmp_path, json.dumps(document))
    with pytest.raises(FormatError, match="maps.sketch.path") as caught:
        load_correspondences(path)
    _one_line_error(path, caught.value)


# --------------------------------------------------------------------------- 2: whatever loads saves


@pytest.mark.parametrize(
    "text",
    [
        '"zz": 1e400',
        '"zz": -1e400',
        '"zz": "\\ud800"',
        '"\\udc80": 1',
        '"zz": ["\\udfff", {"\\ud83d": "x"}]',
    ],
)
def test_whatever_loads_saves(tmp_path, text):
    base = json.dumps(_document())
    path = _write_json_text(tmp_path, base[:-1] + ", " + text + "}")
    try:
        corr = load_correspondences(path)
    except FormatError as error:
        _one_line_error(path, error)
        return
    target = tmp_path / "again.json"
    save_correspondences(corr, target, now=NOW)
    assert load_correspondences(target).extra == corr.extra


def test_out_of_range_number_is_refused_naming_the_field(tmp_path):
    path = _write_json_text(tmp_path, json.dumps(_document())[:-1] + ', "zz": {"deep": [1e400]}}')
    with pytest.raises(FormatError, match=r"zz\.deep\[0\]"):
        load_correspondences(path)


def test_lone_surrogate_in_a_note_saves(tmp_path):
    corr = Correspondences(cliques=(Clique(id=1, note="half \ud800 pair"),))
    target = tmp_path / "pair.json"
    save_correspondences(corr, target, now=NOW)
    assert load_correspondences(target).cliques[0].note == "half \ud800 pair"


# --------------------------------------------------------------------------- 3: two writers, saving onto a map


def test_save_detects_a_change_on_disk_since_load(tmp_path):
    target = tmp_path / "pair.json"
    save_correspondences(Correspondences(cliques=(Clique(id=1),)), target, now=NOW)
    first = load_correspondences(target)
    second = load_correspondences(target)
    assert first.loaded_sha256 is not None and first.loaded_sha256 == second.loaded_sha256

    digest = save_correspondences(first.with_clique(Clique(id=2)), target, expected_sha256=first.loaded_sha256)
    assert load_correspondences(target).loaded_sha256 == digest
    before = target.read_bytes()
    with pytest.raises(FileChangedError) as caught:
        save_correspondences(second.with_clique(Clique(id=3)), target, expected_sha256=second.loaded_sha256)
    assert isinstance(caught.value, SaveRefusedError)
    _one_line_error(target, caught.value)
    assert target.read_bytes() == before  # the first session's clique 2 is still there
    # The question answered "overwrite": no expected digest, the save goes through.
    save_correspondences(second.with_clique(Clique(id=3)), target)
    assert [c.id for c in load_correspondences(target).cliques] == [1, 3]


def test_the_digest_check_also_guards_dat_files(tmp_path):
    target = tmp_path / "gt.dat"
    save_dat(Correspondences(cliques=(Clique(id=1, sketch_points=[(1, 1)]),)), target)
    loaded = load_dat(target)
    target.write_text("# - -\n", encoding="utf-8")
    with pytest.raises(FileChangedError):
        save_dat(loaded, target, expected_sha256=loaded.loaded_sha256)


@pytest.mark.parametrize("save", [save_correspondences, save_dat])
def test_saving_onto_a_loaded_map_image_is_refused(tmp_path, save):
    image = tmp_path / "sketch.png"
    image.write_bytes(b"\x89PNG pretend")
    corr = Correspondences(MapRef(path=image), MapRef(path=tmp_path / "model.png"))
    with pytest.raises(SaveRefusedError, match="sketch map"):
        save(corr, image)
    assert image.read_bytes() == b"\x89PNG pretend"
    link = tmp_path / "link.json"
    link.symlink_to(image)
    with pytest.raises(SaveRefusedError):
        save(corr, link)


# --------------------------------------------------------------------------- 4: the .dat header


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


# --------------------------------------------------------------------------- 9, 10: nesting, numbers


@pytest.mark.parametrize("depth", [990, 5000, 100_000])
def test_deep_nesting_is_a_format_error(tmp_path, depth):
    text = json.dumps(_document())[:-1] + ', "zz": ' + "[" * depth + "]" * depth + "}"
    path = _write_json_text(tmp_path, text)
    with pytest.raises(FormatError, match="nest") as caught:
        load_correspondences(path)
    _one_line_error(path, caught.value)


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"id": 1.0}, "cliques[0].id"),
        ({"id": 1e308}, "cliques[0].id"),
        ({"sketch_points": [[1.0, 2]]}, "cliques[0].sketch_points[0][0]"),
        ({"sketch_regions": [2.0]}, "cliques[0].sketch_regions[0]"),
        ({"score": "1e400"}, "cliques[0].score"),
        ({"id": "9" * 5000}, "cliques[0].id"),
    ],
)
def test_numbers_that_crashed_are_format_errors(tmp_path, change, field):
    document = _document()
    document["cliques"][0].update({key: "@@" if isinstance(value, str) else value for key, value in change.items()})
    text = json.dumps(document)
    for value in change.values():
        if isinstance(value, str):
            text = text.replace('"@@"', value)
    path = _write_json_text(tmp_path, text)
    with pytest.raises(FormatError) as caught:
        load_correspondences(path)
    assert caught.value.field == field
    _one_line_error(path, caught.value)


def test_float_sizes_are_format_errors(tmp_path):
    document = _document()
    document["maps"]["sketch"]["size"] = [446.0, 774.0]
    path = _write_json_text(tmp_path, json.dumps(document))
    with pytest.raises(FormatError) as caught:
        load_correspondences(path)
    assert caught.value.field in ("maps.sketch.size[0]", "maps.sketch.size[1]")


def test_huge_integer_in_a_dat_file_is_a_format_error(tmp_path):
    path = tmp_path / "gt.dat"
    path.write_text("# a.png b.png\n# 0match set\n# map1\n" + "9" * 5000 + " 1\n# map2\n", encoding="utf-8")
    with pytest.raises(FormatError, match="line 4") as caught:
        load_dat(path)
    _one_line_error(path, caught.value)


def test_nul_in_a_dat_header_is_a_format_error(tmp_path):
    path = tmp_path / "gt.dat"
    path.write_text("# a%00.png b.png\n", encoding="utf-8")
    with pytest.raises(FormatError, match="line 1"):
        load_dat(path)


# --------------------------------------------------------------------------- 14: say so


def test_sha256_mismatch_warns_when_the_map_is_given(tmp_path):
    grey = np.full((4, 4), 255, np.uint8)
    sketch = map_from_array(grey)
    sketch = type(sketch)(free=sketch.free, path=tmp_path / "a.png", sha256="b" * 64, image=sketch.image)
    document = _document()
    document["maps"]["sketch"]["sha256"] = "a" * 64
    path = _write_json_text(tmp_path, json.dumps(document))
    with pytest.warns(MapChangedWarning, match="sketch"):
        load_correspondences(path, sketch_map=sketch)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_correspondences(path)  # no map given: nothing to compare
        same = type(sketch)(free=sketch.free, path=sketch.path, sha256="a" * 64)
        load_correspondences(path, sketch_map=same)


def test_region_ids_that_disagree_with_the_points_are_reported(tmp_path):
    labels = np.array([[1, 1, 0, 2, 2]], dtype=np.int32)
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(0, 0)], metric_points=[(0, 4)], sketch_regions=[1], metric_regions=[2]),
            Clique(id=7, sketch_points=[(0, 4)], metric_points=[(0, 0)], sketch_regions=[1], metric_regions=[1]),
        )
    )
    with pytest.warns(RegionsRecomputedWarning, match=r"clique 7\b"):
        done = assign_regions(corr, labels, labels)
    assert done.cliques[1].sketch_regions == (2,)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assign_regions(done, labels, labels)
        # Cliques without region ids yet (a .dat file) are filled in silently.
        assign_regions(
            done.with_cliques(Clique(id=c.id, sketch_points=c.sketch_points) for c in done.cliques), labels, labels
        )


@pytest.mark.parametrize("name", ["pair\x00.json", "pair\ud800.json"])
@pytest.mark.parametrize("save", [save_correspondences, save_dat])
def test_unusable_target_names_are_a_typed_error_not_unicode_or_value_error(tmp_path, name, save):
    with pytest.raises(SaveRefusedError, match="file name"):
        save(Correspondences(), tmp_path / name)
    assert list(tmp_path.iterdir()) == []
