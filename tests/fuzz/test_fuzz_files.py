"""Fuzzing the file formats (hypothesis): whatever loads saves and reloads equal; every failure
is one UrsimError naming the file, on one line.

Formats: correspondence JSON, the original .dat, map images, ROS map_server YAML. Inputs are
generated values (round trips) and mutated valid files (bit flips, cuts, splices, random
bytes after real signatures), the kinds of damage a disk, a download or a hand edit does.
"""

from __future__ import annotations

import io
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from PIL import Image

from ursim_core.correspondences import (
    Clique,
    Correspondences,
    MapRef,
    correspondences_to_json,
    json_codec,
    json_text,
    load_correspondences,
    load_dat,
    save_correspondences,
    save_dat,
    schema,
)
from ursim_core.errors import FormatError, MapError, UrsimError
from ursim_core.io import load_map

NOW = "2024-05-01T12:00:00Z"
FUZZ = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


def _folder(factory) -> Path:
    # hypothesis runs many examples per test: one fresh folder each, under pytest's own
    # temporary root (session-scoped, cleaned by pytest), as tmp_path would be shared.
    return factory.mktemp("fuzz")


def _assert_one_clear_error(error: UrsimError, path: Path) -> None:
    message = str(error)
    assert "\n" not in message, message
    assert str(path) in message, message
    assert len(message) < 600, message


# --------------------------------------------------------------------------- generated values

# Any Python string, lone surrogates included: whatever a note or key can hold must save.
texts = st.text(st.characters(exclude_categories=()), max_size=12) | st.sampled_from(
    ["\ud800", "a\udce9b", "\udfff\ud83d"]
)
json_leaves = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(10**30), 10**30),
    st.floats(allow_nan=False, allow_infinity=False),
    texts,
)
json_values = st.recursive(
    json_leaves,
    lambda children: st.one_of(st.lists(children, max_size=3), st.dictionaries(texts, children, max_size=3)),
    max_leaves=8,
)
points = st.lists(st.tuples(st.integers(0, 10**6), st.integers(0, 10**6)), max_size=3)
regions = st.lists(st.integers(1, 10**6), max_size=3, unique=True)


@st.composite
def cliques(draw, clique_id: int) -> Clique:
    extra = draw(st.dictionaries(texts.filter(lambda key: key not in json_codec.CLIQUE_KEYS), json_values, max_size=2))
    return Clique(
        id=clique_id,
        sketch_points=draw(points),
        metric_points=draw(points),
        sketch_regions=draw(regions),
        metric_regions=draw(regions),
        source=draw(st.sampled_from(["manual", "auto"])),
        score=draw(st.none() | st.floats(allow_nan=False, allow_infinity=False) | st.integers(-5, 5)),
        note=draw(texts),
        status=draw(st.sampled_from([None, "accepted", "rejected", "pending"])),
        extra=extra,
    )


@st.composite
def documents(draw) -> Correspondences:
    ids = draw(st.lists(st.integers(1, 10**9), max_size=5, unique=True))
    top_extra = draw(st.dictionaries(texts.filter(lambda key: key not in json_codec.TOP_KEYS), json_values, max_size=2))
    # File names: any character but NUL and "/", and the bytes of non-UTF-8 names as
    # os.fsdecode gives them (U+DC80..U+DCFF).
    alphabet = st.characters(exclude_characters="\x00/", exclude_categories=("Cs",)) | st.characters(
        min_codepoint=0xDC80, max_codepoint=0xDCFF
    )
    name = draw(st.text(alphabet, min_size=1, max_size=10).filter(lambda text: text not in (".", "..")))
    return Correspondences(
        MapRef(
            path=Path("/data/maps") / name,
            size=draw(st.none() | st.tuples(st.integers(1, 10**5), st.integers(1, 10**5))),
        ),
        MapRef(segmentation_params=draw(st.dictionaries(texts, json_values, max_size=2))),
        cliques=tuple(draw(cliques(clique_id)) for clique_id in ids),
        annotator=draw(texts),
        extra=top_extra,
    )


@FUZZ
@given(corr=documents())
def test_json_whatever_is_saved_loads_equal_and_saves_the_same_text(corr, tmp_path_factory):
    folder = _folder(tmp_path_factory)
    target = folder / "pair.json"
    save_correspondences(corr, target, now=NOW)
    first = target.read_bytes()
    first.decode("utf-8")  # the file is valid UTF-8 whatever the strings held
    back = load_correspondences(target)
    assert back.cliques == corr.cliques
    assert back.extra == corr.extra and back.annotator == corr.annotator
    assert os.fsencode(back.sketch.path) == os.fsencode(corr.sketch.path)
    save_correspondences(back, target, now=NOW)
    assert target.read_bytes() == first


@FUZZ
@given(corr=documents())
def test_fast_clique_writer_gives_json_dumps_text(corr):
    # The reference: the whole document through json.dumps(indent=2) and the number-list
    # collapsing, as every version before the fast writer wrote it.
    folder = Path("/data")
    document = json_codec._to_document(corr, folder)
    reference = json_text.collapse_number_lists(json.dumps(document, indent=2, ensure_ascii=False)) + "\n"
    reference = json_text.escape_lone_surrogates(reference)
    assert correspondences_to_json(corr, folder=folder) == reference


clique_like = st.fixed_dictionaries(
    {},
    optional={
        "id": st.one_of(st.integers(-2, 3), st.floats(0, 3), st.booleans(), st.none(), st.text(max_size=2)),
        "sketch_points": st.one_of(
            st.lists(st.lists(st.one_of(st.integers(-1, 3), st.floats(0, 2), st.booleans()), max_size=3), max_size=2),
            st.integers(),
            st.none(),
        ),
        "metric_points": st.lists(st.lists(st.integers(-1, 3), min_size=2, max_size=2), max_size=2),
        "sketch_regions": st.one_of(st.lists(st.one_of(st.integers(-1, 3), st.floats(1, 2)), max_size=2), st.text()),
        "source": st.sampled_from(["manual", "auto", "x", 1, None]),
        "score": st.one_of(st.none(), st.floats(allow_nan=False, allow_infinity=False), st.booleans(), st.text()),
        "note": st.one_of(st.text(max_size=3), st.integers()),
        "status": st.sampled_from(["accepted", "rejected", "pending", None, "done", 0]),
        "other": json_values,
    },
)


@settings(max_examples=300, deadline=None)
@given(item=clique_like | json_values)
def test_fast_clique_check_agrees_with_the_schema_validator(item):
    document = {
        "format": "ursim-correspondences",
        "version": 1,
        "maps": {"sketch": {"path": None}, "metric": {"path": None}},
    }
    document["cliques"] = [item]
    assert schema._clique_is_valid(item) == schema.compiled_validator().is_valid(document)


_map_fields = {
    "path": st.one_of(st.text(min_size=1, max_size=2), st.none(), st.just(""), st.integers()),
    "sha256": st.one_of(
        st.none(),
        st.just("ab" * 32),
        st.text("0123456789abcdefABCDEFg", min_size=63, max_size=65),
        st.just("a" * 64 + "\n"),
        st.integers(),
    ),
    "size": st.one_of(
        st.none(), st.just([3, 4]), st.lists(st.one_of(st.integers(0, 3), st.floats(1, 2), st.booleans()), max_size=3)
    ),
    "segmentation": st.one_of(
        st.none(),
        st.just({"method": "maoris", "params": {}, "labels": "l.png"}),
        st.integers(),
        st.fixed_dictionaries(
            {},
            optional={
                "method": st.one_of(st.none(), st.text(max_size=2), st.integers()),
                "params": st.one_of(
                    st.dictionaries(st.text(max_size=2), st.integers(), max_size=2), st.lists(st.integers())
                ),
                "labels": st.one_of(st.none(), st.text(max_size=2), st.booleans()),
            },
        ),
    ),
    "other": json_values,
}
# Mostly with a path (as every written map has), so that valid maps are common.
map_like = st.fixed_dictionaries(
    {"path": _map_fields["path"]}, optional={key: value for key, value in _map_fields.items() if key != "path"}
) | st.fixed_dictionaries({}, optional=_map_fields)
stamps = st.one_of(
    st.sampled_from(
        ["", "2024-05-01", "2024-05-01T12:00:00Z", "2024-05-01T12:00:00.5+02:00", "2024-05-01\n", "x", "2024"]
    ),
    st.text(max_size=4),
    st.integers(),
)
_head_fields = {
    "annotator": st.one_of(st.text(max_size=2), st.integers(), st.none()),
    "created": stamps,
    "modified": stamps,
    "other": json_values,
}
# The required keys present and nearly right, or anything missing.
head_like = st.fixed_dictionaries(
    {
        "format": st.sampled_from(["ursim-correspondences"] * 4 + ["other", 1]),
        "version": st.sampled_from([1, 1, 1, 1.0, True, 2, "1"]),
        "maps": st.fixed_dictionaries({"sketch": map_like, "metric": map_like}, optional={"other": json_values})
        | st.integers(),
        "cliques": st.one_of(st.just([]), st.just([]), st.integers()),
    },
    optional=_head_fields,
) | st.fixed_dictionaries(
    {"cliques": st.just([])},
    optional={
        "format": st.just("ursim-correspondences"),
        "version": st.just(1),
        "maps": st.fixed_dictionaries({}, optional={"sketch": map_like, "metric": map_like}),
        **_head_fields,
    },
)


@settings(max_examples=600, deadline=None)
@given(document=head_like | json_values)
def test_fast_head_check_never_passes_what_the_schema_validator_refuses(document):
    # The fast check may refuse more (the validator then decides), never less; on every
    # document outside the few JSON-equal-but-other-type values it agrees exactly.
    fast, slow = schema._head_is_valid(document), schema.compiled_validator().is_valid(document)
    assert slow or not fast
    if isinstance(document, dict) and type(document.get("version")) in (int, str, type(None)):
        assert fast == slow


def test_fast_head_check_accepts_a_saved_file(tmp_path):
    target = tmp_path / "pair.json"
    corr = Correspondences(annotator="ana", cliques=(Clique(id=1, sketch_points=((1, 2),), metric_points=((3, 4),)),))
    save_correspondences(corr, target, now=NOW)
    assert schema._head_is_valid(json.loads(target.read_text()))


# --------------------------------------------------------------------------- mutated files


def _valid_json_bytes() -> bytes:
    corr = Correspondences(
        MapRef(path=Path("/m/a.png"), sha256="a" * 64, size=(40, 60), segmentation_method="maoris"),
        MapRef(path=Path("/m/b.png")),
        cliques=(
            Clique(id=1, sketch_points=[(3, 4)], metric_points=[(5, 6), (7, 8)], sketch_regions=[1], score=0.5),
            Clique(id=5, sketch_points=[(10, 11)], metric_points=[], note="é", status="pending", extra={"k": [1, 2]}),
        ),
        annotator="ana",
        extra={"zz": {"deep": [1.5, None, True]}},
    )
    return correspondences_to_json(corr, folder="/m").encode("utf-8")


VALID_JSON = _valid_json_bytes()


@st.composite
def mutations(draw, valid: bytes) -> bytes:
    """A valid file damaged the way files get damaged: flips, cuts, splices, insertions."""
    data = bytearray(valid)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["flip", "cut", "insert", "delete", "replace", "splice"]))
        position = draw(st.integers(0, max(len(data) - 1, 0)))
        if kind == "flip" and data:
            data[position] ^= 1 << draw(st.integers(0, 7))
        elif kind == "cut":
            del data[position:]
        elif kind == "insert":
            data[position:position] = draw(
                st.sampled_from(
                    [b"[", b"{", b"]", b"}", b'"', b"\\", b",", b"1e400", b"-", b"\x00", b"\xff", b"\\ud800"]
                )
                | st.binary(max_size=6)
            )
        elif kind == "delete":
            del data[position : position + draw(st.integers(1, 8))]
        elif kind == "replace":
            data[position : position + 1] = draw(
                st.sampled_from([b"1.0", b"true", b"null", b'"x"', b"[]", b"{}", b"9" * 30])
            )
        elif kind == "splice":
            start = draw(st.integers(0, len(valid)))
            data[position:position] = valid[start : start + draw(st.integers(1, 40))]
    return bytes(data)


@FUZZ
@given(data=mutations(VALID_JSON))
def test_json_every_failure_is_one_format_error_and_every_success_saves(data, tmp_path_factory):
    folder = _folder(tmp_path_factory)
    path = folder / "pair.json"
    path.write_bytes(data)
    try:
        corr = load_correspondences(path)
    except FormatError as error:
        _assert_one_clear_error(error, path)
        return
    again = folder / "again.json"
    save_correspondences(corr, again, now=NOW)
    back = load_correspondences(again)
    assert back.cliques == corr.cliques and back.extra == corr.extra


VALID_DAT = b"""# /home/a/sketches/00.png ../../model_simple.png
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

"""


@FUZZ
@given(data=mutations(VALID_DAT))
def test_dat_every_failure_is_one_format_error_and_every_success_round_trips(data, tmp_path_factory):
    folder = _folder(tmp_path_factory)
    path = folder / "gt.dat"
    path.write_bytes(data)
    try:
        corr = load_dat(path)
    except FormatError as error:
        _assert_one_clear_error(error, path)
        return
    again = folder / "again.dat"
    save_dat(corr, again)
    assert load_dat(again) == corr


def _image_bytes(fmt: str) -> bytes:
    grey = np.zeros((12, 16), np.uint8)
    grey[3:9, 2:14] = 255
    buffer = io.BytesIO()
    Image.fromarray(grey).save(buffer, format=fmt)
    return buffer.getvalue()


IMAGES = {fmt: _image_bytes(fmt) for fmt in ("PNG", "BMP", "TIFF", "JPEG", "PPM")}


@FUZZ
@given(fmt=st.sampled_from(sorted(IMAGES)), data=st.data())
def test_map_every_failure_is_one_map_error(fmt, data, tmp_path_factory):
    damaged = data.draw(mutations(IMAGES[fmt]))
    folder = _folder(tmp_path_factory)
    path = folder / f"map.{fmt.lower()}"
    path.write_bytes(damaged)
    try:
        loaded = load_map(path, max_pixels=100_000)
    except MapError as error:
        _assert_one_clear_error(error, path)
        return
    assert loaded.free.any() and loaded.free.size <= 100_000


yaml_fragments = st.sampled_from(
    [
        "image: room.png\n",
        "resolution: 0.05\n",
        "origin: [0.0, 0.0, 0.0]\n",
        "negate: 1\n",
        "mode: scale\n",
        "free_thresh: 0.2\n",
        "occupied_thresh: 0.7\n",
        "a: &x [1, 2]\n",
        "b: *x\n",
        "resolution: " + "9" * 500 + "\n",
        "origin: [1e400, 0, 0]\n",
        "image: !!python/object:os.system x\n",
        "\t",
        "---\n",
        "[[[[[[[[",
        "image: room\x00.png\n",
        "image: missing.png\n",
        ": :\n",
        "mode: [1, {a: b}]\n",
        "'" + "x" * 300 + "'\n",
    ]
)


@FUZZ
@given(parts=st.lists(yaml_fragments, min_size=1, max_size=6), noise=st.binary(max_size=4))
def test_yaml_every_failure_is_one_map_error(parts, noise, tmp_path_factory):
    folder = _folder(tmp_path_factory)
    grey = np.zeros((6, 6), np.uint8)
    grey[1:5, 1:5] = 255
    Image.fromarray(grey).save(folder / "room.png")
    path = folder / "map.yaml"
    path.write_bytes("".join(parts).encode("utf-8") + noise)
    try:
        loaded = load_map(path)
    except MapError as error:
        _assert_one_clear_error(error, path)
        return
    assert loaded.resolution is not None and math.isfinite(loaded.resolution)


@pytest.mark.parametrize("size", [0, 1, 7, 8, 30, 4096])
def test_random_bytes_after_real_signatures_are_one_map_error(size, tmp_path_factory):
    generator = np.random.default_rng(size)
    folder = _folder(tmp_path_factory)
    for signature in (b"\x89PNG\r\n\x1a\n", b"II*\x00", b"MM\x00*", b"\xff\xd8\xff", b"BM", b"P5\n", b"GIF89a", b""):
        path = folder / "map.png"
        path.write_bytes(signature + generator.integers(0, 256, size, dtype=np.uint8).tobytes())
        try:
            load_map(path, max_pixels=100_000)
        except MapError as error:
            _assert_one_clear_error(error, path)


def test_generated_documents_cover_the_hard_cases():
    # The generators must reach lone surrogates and unknown keys, or the round trip proves little.
    @settings(max_examples=30, deadline=None, database=None)
    @given(corr=documents())
    def probe(corr):
        found["surrogate"] |= any(any("\ud800" <= char <= "\udfff" for char in clique.note) for clique in corr.cliques)
        found["extra"] |= bool(corr.extra) or any(clique.extra for clique in corr.cliques)

    found = {"surrogate": False, "extra": False}
    probe()
    assert found == {"surrogate": True, "extra": True}
