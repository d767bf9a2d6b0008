"""Guarded saves of correspondence files (ursim_core.correspondences.files): changed on disk, onto a map, bad names."""

from __future__ import annotations

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
from ursim_core.errors import FileChangedError, SaveRefusedError

NOW = "2024-05-01T12:00:00Z"


# --------------------------------------------------------------------------- issue 12, item 3: two writers, saving onto a map


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
    one_line_error(target, caught.value)
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


@pytest.mark.parametrize("name", ["pair\x00.json", "pair\ud800.json"])
@pytest.mark.parametrize("save", [save_correspondences, save_dat])
def test_unusable_target_names_are_a_typed_error_not_unicode_or_value_error(tmp_path, name, save):
    with pytest.raises(SaveRefusedError, match="file name"):
        save(Correspondences(), tmp_path / name)
    assert list(tmp_path.iterdir()) == []
