"""Correspondence values, the JSON format (round trip, unknown keys, every bad file), regions from points."""

from __future__ import annotations

import dataclasses
import json
import math
import os
from pathlib import Path

import jsonschema
import numpy as np
import pytest

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    assign_regions,
    correspondences_schema,
    from_pairs,
    json_codec,
    load_correspondences,
    regions_at_points,
    save_correspondences,
)
from ursim_core.errors import FormatError, SegmentationError

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


# --------------------------------------------------------------------------- values


def test_clique_normalises_sequences_and_numpy_integers():
    clique = Clique(
        id=np.int64(3),
        sketch_points=np.array([[1, 2], [3, 4]]),
        metric_points=[[5, 6]],
        sketch_regions=[np.int32(7)],
        metric_regions=(8, 9),
        score=np.float32(0.5),
    )
    assert clique.id == 3 and type(clique.id) is int
    assert clique.sketch_points == ((1, 2), (3, 4))
    assert all(type(value) is int for point in clique.sketch_points for value in point)
    assert clique.metric_points == ((5, 6),)
    assert clique.sketch_regions == (7,) and clique.metric_regions == (8, 9)
    assert clique.score == 0.5 and type(clique.score) is float


@pytest.mark.parametrize(
    "arguments",
    [
        {"id": 0},
        {"id": 1.0},
        {"id": 1, "sketch_points": [(1, 2, 3)]},
        {"id": 1, "sketch_points": [(1.5, 2)]},
        {"id": 1, "metric_points": [(-1, 2)]},
        {"id": 1, "sketch_regions": [0]},
        {"id": 1, "source": "robot"},
        {"id": 1, "status": "done"},
        {"id": 1, "score": math.nan},
        {"id": 1, "extra": {"note": "clashes with a field"}},
    ],
)
def test_invalid_clique_values_are_refused(arguments):
    with pytest.raises((ValueError, TypeError)):
        Clique(**arguments)


def test_effective_status_defaults_by_source():
    assert Clique(id=1).effective_status == "accepted"
    assert Clique(id=1, source="auto").effective_status == "pending"
    assert Clique(id=1, source="auto", status="accepted").effective_status == "accepted"


def test_mapref_normalises_and_checks():
    ref = MapRef(path="a/b.png", size=[3, 4], labels_path="c.png")
    assert ref.path == Path("a/b.png") and ref.size == (3, 4)
    with pytest.raises(ValueError):
        MapRef(sha256="xyz")
    with pytest.raises(ValueError):
        MapRef(size=(0, 4))
    with pytest.raises(ValueError):
        MapRef(extra={"path": "x"})


def test_correspondences_refuses_duplicate_ids():
    with pytest.raises(ValueError, match="duplicate clique id 2"):
        Correspondences(cliques=(Clique(id=2), Clique(id=3), Clique(id=2)))


def test_clique_helpers():
    corr = Correspondences(cliques=(Clique(id=3), Clique(id=1)))
    assert Correspondences().next_clique_id() == 1
    assert corr.next_clique_id() == 4
    replaced = corr.with_clique(Clique(id=1, note="changed"))
    assert [c.id for c in replaced.cliques] == [3, 1] and replaced.clique(1).note == "changed"
    appended = corr.with_clique(Clique(id=9))
    assert [c.id for c in appended.cliques] == [3, 1, 9]
    assert [c.id for c in corr.without_clique(3).cliques] == [1]
    assert [c.id for c in corr.with_cliques([Clique(id=5)]).cliques] == [5]
    with pytest.raises(KeyError):
        corr.without_clique(42)
    # Values can be set members and dictionary keys (the GUI keys caches on them).
    assert len({Clique(id=1, extra={"a": [1]}), Clique(id=1, extra={"a": [1]}), Clique(id=2)}) == 2
    assert {corr: "cached"}[Correspondences(cliques=(Clique(id=3), Clique(id=1)))] == "cached"
    # The original is untouched: values, not objects to mutate.
    assert [c.id for c in corr.cliques] == [3, 1]
    with pytest.raises(dataclasses.FrozenInstanceError):
        corr.annotator = "x"


# --------------------------------------------------------------------------- JSON round trip


def test_shipped_schema_is_valid_draft_2020_12():
    schema = correspondences_schema(1)
    jsonschema.Draft202012Validator.check_schema(schema)
    assert schema["properties"]["version"] == {"const": 1}


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


# --------------------------------------------------------------------------- regions at points


def _two_rooms():
    labels = np.zeros((30, 40), dtype=np.int32)
    labels[0:10, 0:10] = 1  # region 1: rows 0-9, cols 0-9
    labels[0:10, 25:40] = 2  # region 2: rows 0-9, cols 25-39
    return labels


def test_point_on_a_region_gets_it():
    assert regions_at_points(_two_rooms(), [(0, 0), (9, 9), (5, 30)]) == [1, 1, 2]


def test_point_on_a_wall_within_tolerance_gets_nearest_region():
    labels = _two_rooms()
    # (5, 16): 7 px from region 1 (col 9), 9 px from region 2 (col 25).
    assert regions_at_points(labels, [(5, 16)]) == [1]
    # (5, 19): 10 px from region 1, 6 px from region 2.
    assert regions_at_points(labels, [(5, 19)]) == [2]
    # (19, 9): exactly 10 px below region 1 is still within the tolerance.
    assert regions_at_points(labels, [(19, 9)]) == [1]


def test_point_beyond_tolerance_is_dropped():
    labels = _two_rooms()
    assert regions_at_points(labels, [(20, 9)]) == [0]  # 11 px below region 1
    assert regions_at_points(labels, [(17, 16)]) == [0]  # sqrt(8^2 + 7^2) = 10.6 px
    assert regions_at_points(labels, [(20, 9)], tolerance=11) == [1]
    assert regions_at_points(labels, [(5, 16)], tolerance=0) == [0]


def test_point_outside_the_image():
    labels = _two_rooms()
    assert regions_at_points(labels, [(-3, 2)]) == [1]
    assert regions_at_points(labels, [(4, 45)]) == [2]
    assert regions_at_points(labels, [(-11, 2)]) == [0]
    assert regions_at_points(labels, [(5, 60)]) == [0]
    assert regions_at_points(labels, [(38, 9)], tolerance=30) == [1]  # 29 px below region 1
    assert regions_at_points(labels, [(40, 9)], tolerance=30) == [0]  # 31 px


def test_regions_at_points_edge_inputs():
    labels = _two_rooms()
    assert regions_at_points(labels, []) == []
    assert regions_at_points(np.zeros((5, 5), dtype=np.int32), [(2, 2)]) == [0]
    assert regions_at_points(labels, [(4.6, 9.4)]) == [1]
    assert regions_at_points(labels, np.array([[0, 0], [5, 30]])) == [1, 2]
    with pytest.raises(ValueError):
        regions_at_points(labels, [(1, 2, 3)])
    with pytest.raises(ValueError):
        regions_at_points(labels[0], [(0, 0)])


def test_many_points_give_a_nearest_region_like_brute_force(monkeypatch):
    from scipy import ndimage

    transforms = []
    real_transform = ndimage.distance_transform_edt

    def counting_transform(*args, **kwargs):
        transforms.append(1)
        return real_transform(*args, **kwargs)

    monkeypatch.setattr(ndimage, "distance_transform_edt", counting_transform)
    generator = np.random.default_rng(7)
    labels = np.zeros((60, 80), dtype=np.int32)
    for region in range(1, 9):
        row, col = generator.integers(0, 55), generator.integers(0, 75)
        labels[row : row + 5, col : col + 5] = region
    points = np.stack([generator.integers(-8, 68, 400), generator.integers(-8, 88, 400)], axis=1)
    tolerance = 6.5
    found = regions_at_points(labels, points, tolerance=tolerance)
    assert len(transforms) == 1
    one_by_one = [regions_at_points(labels, [point], tolerance=tolerance)[0] for point in points]  # window search
    assert len(transforms) == 1

    region_rows, region_cols = np.nonzero(labels)
    for (row, col), region, single in zip(points, found, one_by_one):
        distances = np.hypot(region_rows - row, region_cols - col)
        nearest = distances.min()
        if nearest > tolerance:
            assert region == 0 and single == 0
            continue
        candidates = set(labels[region_rows[distances == nearest], region_cols[distances == nearest]])
        assert region in candidates and single in candidates


# --------------------------------------------------------------------------- assign_regions / from_pairs


def test_assign_regions_dedupes_in_order_and_drops_misses():
    sketch = _two_rooms()
    metric = np.zeros((10, 10), dtype=np.int32)
    metric[:, 5:] = 3
    corr = Correspondences(
        cliques=(
            Clique(id=1, sketch_points=[(5, 30), (1, 1), (6, 31), (29, 0)], metric_points=[(0, 9)]),
            Clique(id=2, sketch_points=[], metric_points=[(0, 0)], sketch_regions=[9]),
        )
    )
    done = assign_regions(corr, sketch, metric)
    assert done.cliques[0].sketch_regions == (2, 1)
    assert done.cliques[0].metric_regions == (3,)
    assert done.cliques[1].sketch_regions == ()
    assert done.cliques[1].metric_regions == (3,)  # (0, 0) is 5 px from region 3
    assert done.cliques[0].sketch_points == corr.cliques[0].sketch_points
    assert assign_regions(corr, sketch, metric, tolerance=2).cliques[1].metric_regions == ()


def test_assign_regions_refuses_labels_of_another_size():
    corr = Correspondences(sketch=MapRef(path="s.png", size=(30, 40)), metric=MapRef(size=(5, 5)))
    with pytest.raises(SegmentationError, match="metric label image is 10x10"):
        assign_regions(corr, _two_rooms(), np.zeros((10, 10), dtype=np.int32))


def test_from_pairs_builds_one_clique_per_pair():
    interior = {1: (4, 5), 2: (6, 30), 10: (1, 1), 11: (8, 8)}
    cliques = from_pairs(
        [(1, 10), (2, 11)],
        sketch_points_of=interior.__getitem__,
        metric_points_of=interior.__getitem__,
        scores=[0.1, 0.25],
        first_id=4,
    )
    assert [clique.id for clique in cliques] == [4, 5]
    assert cliques[0].sketch_points == ((4, 5),) and cliques[0].metric_points == ((1, 1),)
    assert cliques[1].sketch_regions == (2,) and cliques[1].metric_regions == (11,)
    assert [clique.score for clique in cliques] == [0.1, 0.25]
    assert all(clique.source == "auto" and clique.effective_status == "pending" for clique in cliques)
    manual = from_pairs([(1, 10)], sketch_points_of=interior.get, metric_points_of=interior.get, source="manual")
    assert manual[0].source == "manual" and manual[0].score is None
    with pytest.raises(ValueError):
        from_pairs([(1, 10)], sketch_points_of=interior.get, metric_points_of=interior.get, scores=[])


def test_regions_survive_a_json_round_trip_with_points(tmp_path):
    corr = Correspondences(cliques=(Clique(id=1, sketch_points=[(5, 16)], metric_points=[(2, 30)]),))
    labelled = assign_regions(corr, _two_rooms(), _two_rooms())
    save_correspondences(labelled, tmp_path / "p.json", now=NOW)
    loaded = load_correspondences(tmp_path / "p.json")
    assert loaded.cliques[0].sketch_regions == (1,) and loaded.cliques[0].metric_regions == (2,)


# --------------------------------------------------------------------------- documentation


def test_documented_example_is_what_save_writes(tmp_path):
    repo = Path(__file__).resolve().parents[2]
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
