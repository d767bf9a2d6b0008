"""The JSON correspondence file (ursim_core.correspondences.json_codec): round trip, layout, safe saves, bad files."""

from __future__ import annotations

import dataclasses
import json
import math
import os
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from correspondence_helpers import one_line_error

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    json_codec,
    load_correspondences,
    load_dat,
    save_correspondences,
    save_dat,
)
from ursim_core.errors import FormatError, MapChangedWarning
from ursim_core.io import map_from_array

NOW = "2024-05-01T12:00:00Z"
LATER = "2024-05-02T08:30:00Z"


# --------------------------------------------------------------------------- helpers


def _valid_document():
    return {
        "format": "ursim-correspondences",
        "version": 1,
        "annotator": "ana",
        "created": "2024-01-01T00:00:00Z",
        "modified": "2024-01-02T00:00:00Z",
        "maps": {
            "sketch": {
                "path": "maps/sketch.png",
                "sha256": "a" * 64,
                "size": [40, 60],
                "segmentation": {"method": "maoris", "params": {"threshold": 0.25}, "labels": "maps/sketch.labels.png"},
            },
            "metric": {"path": "maps/metric.png", "sha256": None, "size": None, "segmentation": None},
        },
        "cliques": [
            {
                "id": 1,
                "sketch_points": [[3, 4]],
                "metric_points": [[5, 6], [7, 8]],
                "sketch_regions": [1],
                "metric_regions": [2, 3],
                "source": "manual",
            },
            {
                "id": 5,
                "sketch_points": [[10, 11]],
                "metric_points": [[12, 13]],
                "sketch_regions": [4],
                "metric_regions": [4],
                "source": "auto",
                "score": 0.12,
                "note": "corridor",
                "status": "rejected",
            },
        ],
    }


def _write(path, document):
    path.write_text(json.dumps(document), encoding="utf-8")
    return path


def _full_correspondences(folder):
    return Correspondences(
        sketch=MapRef(
            path=folder / "maps" / "sketch.png",
            sha256="0123456789abcdef" * 4,
            size=(40, 60),
            segmentation_method="maoris",
            segmentation_params={"threshold": 0.25, "doors": 40},
            labels_path=folder / "maps" / "sketch.labels.png",
        ),
        metric=MapRef(path=folder / "metric.pgm", size=(30, 30)),
        cliques=(
            Clique(
                id=2, sketch_points=[(1, 2), (3, 4)], metric_points=[(5, 6)], sketch_regions=[7, 8], metric_regions=[9]
            ),
            Clique(id=7, metric_points=[(0, 0)], source="auto", score=-1.5e-07, note='Zoë\'s "room"', status="pending"),
        ),
        annotator="Zoë",
    )


def test_round_trip_is_exact(tmp_path):
    original = _full_correspondences(tmp_path)
    target = tmp_path / "out" / "pair.json"
    target.parent.mkdir()
    save_correspondences(original, target, now=NOW)
    loaded = load_correspondences(target)
    assert loaded == dataclasses.replace(original, created=NOW, modified=NOW)
    save_correspondences(loaded, tmp_path / "out" / "again.json", now=NOW)
    assert load_correspondences(tmp_path / "out" / "again.json") == loaded


def test_second_save_is_byte_identical(tmp_path):
    target = tmp_path / "pair.json"
    save_correspondences(_full_correspondences(tmp_path), target, now=NOW)
    first = target.read_bytes()
    save_correspondences(load_correspondences(target), target, now=NOW)
    assert target.read_bytes() == first


def test_second_save_differs_only_in_modified(tmp_path):
    target = tmp_path / "pair.json"
    save_correspondences(_full_correspondences(tmp_path), target, now=NOW)
    first = target.read_text().splitlines()
    save_correspondences(load_correspondences(target), target)
    second = target.read_text().splitlines()
    changed = [(a, b) for a, b in zip(first, second) if a != b]
    assert len(first) == len(second)
    assert len(changed) <= 1
    assert all(a.strip().startswith('"modified"') for a, _ in changed)
    assert load_correspondences(target).created == NOW


def test_save_sets_created_only_when_empty(tmp_path):
    target = tmp_path / "pair.json"
    save_correspondences(Correspondences(created="2020-01-01T00:00:00Z"), target, now=NOW)
    loaded = load_correspondences(target)
    assert (loaded.created, loaded.modified) == ("2020-01-01T00:00:00Z", NOW)
    save_correspondences(Correspondences(), target, now=LATER)
    loaded = load_correspondences(target)
    assert (loaded.created, loaded.modified) == (LATER, LATER)


def test_layout_is_indented_ordered_and_keeps_points_on_one_line(tmp_path):
    target = tmp_path / "pair.json"
    save_correspondences(_full_correspondences(tmp_path), target, now=NOW)
    text = target.read_text(encoding="utf-8")
    document = json.loads(text)
    assert list(document) == ["format", "version", "annotator", "created", "modified", "maps", "cliques"]
    assert list(document["cliques"][0]) == [
        "id",
        "sketch_points",
        "metric_points",
        "sketch_regions",
        "metric_regions",
        "source",
    ]
    assert list(document["cliques"][1])[-3:] == ["score", "note", "status"]
    assert text.startswith('{\n  "format": "ursim-correspondences",\n')
    assert '      "sketch_points": [\n        [1, 2],\n        [3, 4]\n      ],' in text
    assert '"sketch_regions": [7, 8],' in text
    assert '"size": [40, 60],' in text
    assert '"annotator": "Zoë"' in text  # readable, not \u escapes
    assert text.endswith("}\n")
    assert document["cliques"][1]["score"] == -1.5e-07


def test_paths_are_stored_relative_and_loaded_absolute(tmp_path):
    (tmp_path / "maps").mkdir()
    (tmp_path / "annotations").mkdir()
    corr = Correspondences(
        sketch=MapRef(path=tmp_path / "maps" / "s.png", labels_path=tmp_path / "maps" / "s.labels.png"),
        metric=MapRef(path=tmp_path / "annotations" / "m.png"),
    )
    target = tmp_path / "annotations" / "pair.json"
    save_correspondences(corr, target, now=NOW)
    stored = json.loads(target.read_text())["maps"]
    assert stored["sketch"]["path"] == "../maps/s.png"
    assert stored["sketch"]["segmentation"]["labels"] == "../maps/s.labels.png"
    assert stored["metric"]["path"] == "m.png"
    loaded = load_correspondences(target)
    assert loaded.sketch.path == tmp_path / "maps" / "s.png"
    assert loaded.sketch.path.is_absolute()
    assert loaded.metric.path == tmp_path / "annotations" / "m.png"


def test_relative_in_memory_paths_are_relative_to_the_working_directory(tmp_path, monkeypatch):
    (tmp_path / "sub").mkdir()
    monkeypatch.chdir(tmp_path)
    save_correspondences(Correspondences(sketch=MapRef(path="s.png")), tmp_path / "sub" / "p.json", now=NOW)
    assert json.loads((tmp_path / "sub" / "p.json").read_text())["maps"]["sketch"]["path"] == "../s.png"


def test_minimal_file_gets_defaults(tmp_path):
    document = {
        "format": "ursim-correspondences",
        "version": 1,
        "maps": {"sketch": {"path": None}, "metric": {"path": "m.png"}},
        "cliques": [{"id": 1, "sketch_points": [[1, 1]], "metric_points": []}],
    }
    loaded = load_correspondences(_write(tmp_path / "min.json", document))
    assert loaded.annotator == "" and loaded.created == ""
    assert loaded.sketch == MapRef()
    assert loaded.metric.path == tmp_path / "m.png"
    assert loaded.cliques[0] == Clique(id=1, sketch_points=[(1, 1)])


def test_unknown_keys_are_preserved_at_every_level(tmp_path):
    document = _valid_document()
    document["tool"] = {"name": "other", "list": [1, {"deep": True}]}
    document["maps"]["layout"] = {"path": "layout.png"}
    document["maps"]["sketch"]["drawn_by"] = "participant 7"
    document["maps"]["sketch"]["segmentation"]["runtime_s"] = 1.5
    document["cliques"][0]["colour"] = "#ff0000"
    document["cliques"][1]["history"] = [{"by": "ana", "at": "2024"}]
    source = _write(tmp_path / "in.json", document)

    loaded = load_correspondences(source)
    assert loaded.extra == {"tool": {"name": "other", "list": [1, {"deep": True}]}}
    assert loaded.maps_extra == {"layout": {"path": "layout.png"}}
    assert loaded.sketch.extra == {"drawn_by": "participant 7"}
    assert loaded.sketch.segmentation_extra == {"runtime_s": 1.5}
    assert loaded.cliques[0].extra == {"colour": "#ff0000"}

    target = tmp_path / "out.json"
    save_correspondences(loaded, target, now=NOW)
    written = json.loads(target.read_text())
    assert written["tool"] == document["tool"]
    assert written["maps"]["layout"] == {"path": "layout.png"}
    assert written["maps"]["sketch"]["drawn_by"] == "participant 7"
    assert written["maps"]["sketch"]["segmentation"]["runtime_s"] == 1.5
    assert written["cliques"][0]["colour"] == "#ff0000"
    assert written["cliques"][1]["history"] == [{"by": "ana", "at": "2024"}]
    assert load_correspondences(target) == dataclasses.replace(loaded, modified=NOW)


def test_loaded_values_match_the_file(tmp_path):
    loaded = load_correspondences(_write(tmp_path / "in.json", _valid_document()))
    assert loaded.annotator == "ana"
    assert loaded.sketch.path == tmp_path / "maps" / "sketch.png"
    assert loaded.sketch.size == (40, 60)
    assert loaded.sketch.segmentation_params == {"threshold": 0.25}
    assert loaded.sketch.labels_path == tmp_path / "maps" / "sketch.labels.png"
    assert loaded.metric.segmentation_method is None and loaded.metric.size is None
    second = loaded.cliques[1]
    assert (second.id, second.source, second.score, second.note, second.status) == (
        5,
        "auto",
        0.12,
        "corridor",
        "rejected",
    )
    assert loaded.cliques[0].metric_points == ((5, 6), (7, 8))


# --------------------------------------------------------------------------- saving safely


def test_save_refuses_non_json_extra_and_writes_nothing(tmp_path):
    target = tmp_path / "pair.json"
    for bad in ({"when": object()}, {"ratio": math.inf}):
        with pytest.raises(FormatError) as caught:
            save_correspondences(Correspondences(extra=bad), target, now=NOW)
        assert caught.value.path == target
    assert not target.exists()
    assert list(tmp_path.iterdir()) == []


def test_save_refuses_an_invalid_document(tmp_path):
    target = tmp_path / "pair.json"
    target.write_text("old")
    # A timestamp that is not ISO-8601 would make the file unreadable: never written.
    with pytest.raises(FormatError) as caught:
        save_correspondences(Correspondences(), target, now="yesterday")
    assert caught.value.field in ("created", "modified")
    assert "ISO-8601" in caught.value.problem
    assert target.read_text() == "old"


def test_failed_save_keeps_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "pair.json"
    save_correspondences(_full_correspondences(tmp_path), target, now=NOW)
    before = target.read_bytes()

    def failing_replace(source, destination):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(PermissionError):
        save_correspondences(Correspondences(annotator="other"), target, now=LATER)
    assert target.read_bytes() == before
    assert sorted(path.name for path in tmp_path.iterdir()) == ["pair.json"]


def test_failed_encoding_keeps_the_old_file(tmp_path, monkeypatch):
    target = tmp_path / "pair.json"
    target.write_text("previous")

    def failing_dumps(*args, **kwargs):
        raise ValueError("encoder exploded")

    monkeypatch.setattr(json_codec.json, "dumps", failing_dumps)
    with pytest.raises(FormatError, match="encoder exploded"):
        save_correspondences(Correspondences(), target, now=NOW)
    assert target.read_text() == "previous"
    assert sorted(path.name for path in tmp_path.iterdir()) == ["pair.json"]


# --------------------------------------------------------------------------- bad files


def _mutated(change):
    document = _valid_document()
    change(document)
    return document


BAD_DOCUMENTS = [
    # (id, document or raw text, expected field, text expected in the problem)
    ("array-top", [1, 2], None, "expected a JSON object at the top level, got array"),
    ("wrong-format", _mutated(lambda d: d.update(format="labelme")), "format", "not a URSIM correspondence file"),
    ("no-format", _mutated(lambda d: d.pop("format")), "format", "missing"),
    ("version-2", _mutated(lambda d: d.update(version=2)), "version", "unsupported version 2"),
    ("version-string", _mutated(lambda d: d.update(version="1")), "version", "expected an integer"),
    ("no-version", _mutated(lambda d: d.pop("version")), "version", "missing"),
    ("no-maps", _mutated(lambda d: d.pop("maps")), "maps", "required field is missing"),
    ("no-metric", _mutated(lambda d: d["maps"].pop("metric")), "maps.metric", "required field is missing"),
    ("no-cliques", _mutated(lambda d: d.pop("cliques")), "cliques", "required field is missing"),
    ("cliques-object", _mutated(lambda d: d.update(cliques={})), "cliques", "expected array, got object"),
    ("annotator-number", _mutated(lambda d: d.update(annotator=3)), "annotator", "expected string, got integer"),
    ("bad-created", _mutated(lambda d: d.update(created="last tuesday")), "created", "ISO-8601"),
    ("map-path-number", _mutated(lambda d: d["maps"]["sketch"].update(path=5)), "maps.sketch.path", "got integer 5"),
    (
        "bad-sha",
        _mutated(lambda d: d["maps"]["sketch"].update(sha256="abc")),
        "maps.sketch.sha256",
        "64 hexadecimal digits",
    ),
    ("bad-size", _mutated(lambda d: d["maps"]["sketch"].update(size=[10])), "maps.sketch.size", "exactly 2 items"),
    (
        "params-list",
        _mutated(lambda d: d["maps"]["sketch"]["segmentation"].update(params=[])),
        "maps.sketch.segmentation.params",
        "expected object, got array",
    ),
    ("clique-no-id", _mutated(lambda d: d["cliques"][1].pop("id")), "cliques[1].id", "required field is missing"),
    (
        "clique-no-points",
        _mutated(lambda d: d["cliques"][0].pop("metric_points")),
        "cliques[0].metric_points",
        "required field is missing",
    ),
    ("id-string", _mutated(lambda d: d["cliques"][1].update(id="5")), "cliques[1].id", 'got string "5"'),
    ("id-zero", _mutated(lambda d: d["cliques"][0].update(id=0)), "cliques[0].id", "got 0"),
    (
        "point-one-value",
        _mutated(lambda d: d["cliques"][1].update(sketch_points=[[1]])),
        "cliques[1].sketch_points[0]",
        "[row, col] pair of non-negative integers (exactly 2 items), got 1 item",
    ),
    (
        "point-three-values",
        _mutated(lambda d: d["cliques"][0]["metric_points"].append([1, 2, 3])),
        "cliques[0].metric_points[2]",
        "got 3 items",
    ),
    (
        "point-float",
        _mutated(lambda d: d["cliques"][0].update(sketch_points=[[1.5, 2]])),
        "cliques[0].sketch_points[0][0]",
        "expected integer, got number 1.5",
    ),
    (
        "point-negative",
        _mutated(lambda d: d["cliques"][0].update(sketch_points=[[1, -2]])),
        "cliques[0].sketch_points[0][1]",
        "got -2",
    ),
    (
        "point-not-list",
        _mutated(lambda d: d["cliques"][0].update(sketch_points=[{"row": 1, "col": 2}])),
        "cliques[0].sketch_points[0]",
        "expected [row, col] pair",
    ),
    (
        "region-zero",
        _mutated(lambda d: d["cliques"][0].update(metric_regions=[2, 0])),
        "cliques[0].metric_regions[1]",
        "region id",
    ),
    (
        "bad-source",
        _mutated(lambda d: d["cliques"][0].update(source="robot")),
        "cliques[0].source",
        'one of "manual", "auto"',
    ),
    (
        "bad-status",
        _mutated(lambda d: d["cliques"][1].update(status="done")),
        "cliques[1].status",
        '"accepted", "rejected", "pending"',
    ),
    (
        "score-string",
        _mutated(lambda d: d["cliques"][1].update(score="high")),
        "cliques[1].score",
        "expected number or null",
    ),
    (
        "duplicate-ids",
        _mutated(lambda d: d["cliques"][1].update(id=1)),
        "cliques[1].id",
        "duplicate clique id 1 (also used by cliques[0])",
    ),
]


@pytest.mark.parametrize(
    ("document", "field", "problem"),
    [case[1:] for case in BAD_DOCUMENTS],
    ids=[case[0] for case in BAD_DOCUMENTS],
)
def test_bad_documents_name_file_and_field(tmp_path, document, field, problem):
    path = _write(tmp_path / "bad.json", document)
    with pytest.raises(FormatError) as caught:
        load_correspondences(path)
    error = caught.value
    assert error.path == path
    assert error.field == field
    assert problem in error.problem
    assert str(path) in str(error)


def test_version_error_lists_supported_versions(tmp_path):
    path = _write(tmp_path / "v2.json", _mutated(lambda d: d.update(version=2)))
    with pytest.raises(FormatError, match=r"reads version\(s\) 1"):
        load_correspondences(path)


def test_several_problems_are_counted(tmp_path):
    document = _mutated(lambda d: (d.update(annotator=1), d["cliques"][0].update(source="x")))
    with pytest.raises(FormatError, match=r"and 1 more problem\)"):
        load_correspondences(_write(tmp_path / "two.json", document))


@pytest.mark.parametrize(
    ("content", "problem"),
    [
        (b'{\n  "format": "ursim-correspondences",\n  "version": 1,\n  oops\n}', "line 4, column 3"),
        (b"", "line 1, column 1"),
        (b"\x89PNG\r\n\x1a\n\x00\x00", "not UTF-8"),
        (b'{"format": "ursim-correspondences", "format": "x"}', "key 'format' appears twice"),
        (b'{"score": NaN}', "NaN is not a JSON number"),
    ],
    ids=["syntax", "empty", "binary", "duplicate-key", "nan"],
)
def test_unparsable_files_are_reported_with_position(tmp_path, content, problem):
    path = tmp_path / "broken.json"
    path.write_bytes(content)
    with pytest.raises(FormatError) as caught:
        load_correspondences(path)
    assert caught.value.path == path
    assert problem in caught.value.problem


def test_missing_file_and_folder(tmp_path):
    with pytest.raises(FormatError, match="file not found") as caught:
        load_correspondences(tmp_path / "absent.json")
    assert caught.value.path == tmp_path / "absent.json"
    with pytest.raises(FormatError, match="folder"):
        load_correspondences(tmp_path)


def test_utf8_byte_order_mark_is_accepted(tmp_path):
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(_valid_document()).encode())
    assert load_correspondences(path).annotator == "ana"


def test_older_versions_go_through_the_migration_table(tmp_path, monkeypatch):
    def from_version_0(document):
        upgraded = dict(document, version=1)
        upgraded["cliques"] = [dict(clique, id=clique.pop("number")) for clique in document["cliques"]]
        return upgraded

    monkeypatch.setitem(json_codec._MIGRATIONS, 0, from_version_0)
    document = _valid_document()
    document["version"] = 0
    for clique in document["cliques"]:
        clique["number"] = clique.pop("id")
    loaded = load_correspondences(_write(tmp_path / "old.json", document))
    assert [clique.id for clique in loaded.cliques] == [1, 5]


# =========================================================================== issue 12
# Each defect the reliability pass found in correspondence files, reproduced (items by number).

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


# --------------------------------------------------------------------------- issue 12, item 1: file names


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
    one_line_error(path, caught.value)


# --------------------------------------------------------------------------- issue 12, item 2: whatever loads saves


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
        one_line_error(path, error)
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


# --------------------------------------------------------------------------- issue 12, items 9 and 10: nesting, numbers


@pytest.mark.parametrize("depth", [990, 5000, 100_000])
def test_deep_nesting_is_a_format_error(tmp_path, depth):
    text = json.dumps(_document())[:-1] + ', "zz": ' + "[" * depth + "]" * depth + "}"
    path = _write_json_text(tmp_path, text)
    with pytest.raises(FormatError, match="nest") as caught:
        load_correspondences(path)
    one_line_error(path, caught.value)


@pytest.mark.parametrize(
    ("change", "field"),
    [
        ({"id": 1.0}, "cliques[0].id"),
        ({"id": 1e308}, "cliques[0].id"),
        ({"sketch_points": [[1.0, 2]]}, "cliques[0].sketch_points[0][0]"),
        ({"sketch_regions": [2.0]}, "cliques[0].sketch_regions[0]"),
        ({"score": "1e400"}, "cliques[0].score"),
        ({"id": "9" * 5000}, "cliques[0].id"),
        # Too large for a float but not for int(): loaded, then an OverflowError in the first
        # float() (ursim goal, match --reference, locate).
        ({"sketch_points": "[[" + "9" * 400 + ", 2]]"}, "cliques[0].sketch_points[0][0]"),
        ({"metric_regions": "[" + "9" * 309 + "]"}, "cliques[0].metric_regions[0]"),
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
    one_line_error(path, caught.value)


def test_float_sizes_are_format_errors(tmp_path):
    document = _document()
    document["maps"]["sketch"]["size"] = [446.0, 774.0]
    path = _write_json_text(tmp_path, json.dumps(document))
    with pytest.raises(FormatError) as caught:
        load_correspondences(path)
    assert caught.value.field in ("maps.sketch.size[0]", "maps.sketch.size[1]")


# --------------------------------------------------------------------------- issue 12, item 14: say so


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


def test_the_warning_of_a_map_without_a_file_names_no_none(tmp_path):
    from ursim_core.correspondences import check_maps

    grey = np.full((4, 4), 255, np.uint8)
    drawn = type(map_from_array(grey))(free=grey > 0, sha256="b" * 64)  # made in code: no path
    corr = Correspondences(sketch=MapRef(sha256="a" * 64))
    with pytest.warns(MapChangedWarning) as caught:
        check_maps(corr, drawn, None, tmp_path / "pair.json")
    assert "None" not in str(caught[0].message) and "the sketch map is not the one" in str(caught[0].message)


# --------------------------------------------------------------------------- documentation


def test_documented_example_is_what_save_writes(tmp_path):
    repo = Path(__file__).resolve().parents[3]
    documents = [repo / "README.md"]
    blocks = [
        block
        for document in documents
        if document.is_file()
        for block in document.read_text(encoding="utf-8").split("```json\n")[1:]
        if '"format": "ursim-correspondences"' in block
    ]
    assert blocks, "the correspondence format example is missing from the documentation"
    example = blocks[0].split("```")[0]
    source = tmp_path / "example.json"
    source.write_text(example, encoding="utf-8")
    loaded = load_correspondences(source)
    save_correspondences(loaded, tmp_path / "again.json", now=loaded.modified)
    assert (tmp_path / "again.json").read_text(encoding="utf-8") == example
