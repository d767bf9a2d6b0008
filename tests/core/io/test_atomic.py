"""Atomic writes (ursim_core.io.atomic): the old file survives every failure, no temporary file is left behind."""

from __future__ import annotations

import os
import stat
import sys

import pytest

from ursim_core.io import atomic
from ursim_core.io.atomic import atomic_write_bytes, atomic_write_text

posix_only = pytest.mark.skipif(sys.platform == "win32", reason="POSIX permission bits and symlinks")


def _names(folder):
    return sorted(entry.name for entry in folder.iterdir())


def test_creates_new_file_with_exact_bytes(tmp_path):
    target = tmp_path / "new.bin"
    atomic_write_bytes(target, b"\x00\x01binary\r\n")
    assert target.read_bytes() == b"\x00\x01binary\r\n"
    assert _names(tmp_path) == ["new.bin"]


def test_replaces_existing_file(tmp_path):
    target = tmp_path / "data.txt"
    target.write_bytes(b"old content that is longer")
    atomic_write_bytes(target, b"new")
    assert target.read_bytes() == b"new"
    assert _names(tmp_path) == ["data.txt"]


def test_accepts_any_bytes_like_object(tmp_path):
    atomic_write_bytes(tmp_path / "a", bytearray(b"abc"))
    atomic_write_bytes(tmp_path / "b", memoryview(b"xyz"))
    assert (tmp_path / "a").read_bytes() == b"abc"
    assert (tmp_path / "b").read_bytes() == b"xyz"


def test_text_is_written_without_newline_translation(tmp_path):
    target = tmp_path / "t.txt"
    atomic_write_text(target, "é\nline\n")
    assert target.read_bytes() == "é\nline\n".encode()
    atomic_write_text(target, "é", encoding="latin-1")
    assert target.read_bytes() == b"\xe9"


def test_unencodable_text_writes_nothing(tmp_path):
    target = tmp_path / "t.txt"
    target.write_text("old")
    with pytest.raises(UnicodeEncodeError):
        atomic_write_text(target, "\u20ac", encoding="ascii")
    assert target.read_text() == "old"
    assert _names(tmp_path) == ["t.txt"]


def test_failed_rename_keeps_old_file_and_removes_temp(tmp_path, monkeypatch):
    target = tmp_path / "keep.json"
    target.write_bytes(b"original")
    failure = OSError(28, "No space left on device")

    def failing_replace(source, destination):
        raise failure

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError) as caught:
        atomic_write_bytes(target, b"replacement")
    assert caught.value is failure
    assert target.read_bytes() == b"original"
    assert _names(tmp_path) == ["keep.json"]


def test_failed_sync_keeps_old_file_and_removes_temp(tmp_path, monkeypatch):
    target = tmp_path / "keep.json"
    target.write_bytes(b"original")

    def failing_fsync(descriptor):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(os, "fsync", failing_fsync)
    with pytest.raises(OSError, match="Input/output error"):
        atomic_write_text(target, "replacement")
    assert target.read_bytes() == b"original"
    assert _names(tmp_path) == ["keep.json"]


def test_missing_folder_raises_and_creates_nothing(tmp_path):
    with pytest.raises(FileNotFoundError):
        atomic_write_bytes(tmp_path / "absent" / "file.bin", b"x")
    assert _names(tmp_path) == []


@posix_only
def test_existing_permission_bits_are_kept(tmp_path):
    target = tmp_path / "private.json"
    target.write_bytes(b"old")
    os.chmod(target, 0o600)
    atomic_write_bytes(target, b"new")
    assert stat.S_IMODE(os.stat(target).st_mode) == 0o600


@posix_only
def test_new_file_mode_follows_umask(tmp_path):
    previous = os.umask(0o027)
    try:
        atomic_write_bytes(tmp_path / "f", b"x")
    finally:
        os.umask(previous)
    assert stat.S_IMODE(os.stat(tmp_path / "f").st_mode) == 0o640


@posix_only
def test_symlink_is_kept_and_its_target_replaced(tmp_path):
    real = tmp_path / "real.txt"
    real.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    atomic_write_text(link, "new")
    assert link.is_symlink()
    assert real.read_text() == "new"
    assert _names(tmp_path) == ["link.txt", "real.txt"]


# --------------------------------------------------------------------------- issue 12 item 15


def test_stale_temporary_files_of_our_pattern_are_removed_on_the_next_save(tmp_path):
    import time

    from ursim_core.io.atomic import STALE_TEMP_SECONDS

    target = tmp_path / "pair.json"
    old = time.time() - STALE_TEMP_SECONDS - 60
    stale = tmp_path / ".pair.json.0badc0de.tmp"
    fresh = tmp_path / ".pair.json.12345678.tmp"  # a writer that may still be running
    other = tmp_path / ".other.json.0badc0de.tmp"  # another file's: not ours to judge here
    unlike = tmp_path / ".pair.json.notours.tmp"  # not our pattern
    for path in (stale, fresh, other, unlike):
        path.write_bytes(b"partial")
    for path in (stale, other, unlike):
        os.utime(path, (old, old))
    atomic_write_bytes(target, b"new")
    assert _names(tmp_path) == sorted([fresh.name, other.name, unlike.name, target.name])


# --------------------------------------------------------------------------- scratch folders (the staged outputs of ursim_core.cli.common)


def test_saves_into_a_scratch_folder_sync_their_content_but_not_the_folder(tmp_path, directory_syncs):
    synced = directory_syncs
    with atomic.scratch_directory(tmp_path):
        atomic.atomic_write_bytes(tmp_path / "a.bin", b"a")
    assert synced == []
    atomic.atomic_write_bytes(tmp_path / "b.bin", b"b")
    assert synced == [str(tmp_path)]
    assert (tmp_path / "a.bin").read_bytes() == b"a" and atomic._scratch == {}
