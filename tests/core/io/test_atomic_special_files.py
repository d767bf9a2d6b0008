"""Atomic writes onto what is not a regular file (ursim_core.io.atomic): a device or a pipe with a
reader is written through, never replaced; a pipe without one, a folder or a socket is refused at
once; every error names the caller's path."""

from __future__ import annotations

import errno
import os
import socket
import stat
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from ursim_core.io.atomic import atomic_write_bytes, atomic_write_text

posix_only = pytest.mark.skipif(sys.platform == "win32", reason="POSIX special files")


def _names(folder):
    return sorted(entry.name for entry in folder.iterdir())


def _char_device(path, major: int, minor: int):
    """A character device node at ``path`` (``mknod``), or skip: only root may make one, and some
    containers refuse it even to root."""
    if not hasattr(os, "mknod") or os.geteuid() != 0:
        pytest.skip("making a device node (mknod) needs root")
    try:
        os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(major, minor))
    except OSError as error:
        pytest.skip(f"mknod is not allowed here: {error.strerror}")
    return path


@posix_only
def test_a_null_device_is_written_through_and_stays_a_device(tmp_path):
    null = _char_device(tmp_path / "null", 1, 3)
    atomic_write_text(null, '{"goal": 1}\n')
    assert stat.S_ISCHR(os.stat(null).st_mode)
    assert _names(tmp_path) == ["null"]


@posix_only
def test_a_full_device_gives_no_space_naming_the_path_and_stays_a_device(tmp_path):
    full = _char_device(tmp_path / "full", 1, 7)
    with pytest.raises(OSError) as caught:
        atomic_write_bytes(full, b"x" * 10)
    assert caught.value.errno == errno.ENOSPC
    assert caught.value.filename == str(full)
    assert stat.S_ISCHR(os.stat(full).st_mode)
    assert _names(tmp_path) == ["full"]


@posix_only
def test_a_link_to_a_device_is_written_through(tmp_path):
    null = _char_device(tmp_path / "null", 1, 3)
    link = tmp_path / "out.json"
    link.symlink_to(null)
    atomic_write_text(link, "{}\n")
    assert link.is_symlink() and stat.S_ISCHR(os.stat(null).st_mode)


def test_a_folder_is_refused_naming_it(tmp_path):
    folder = tmp_path / "out.json"
    folder.mkdir()
    with pytest.raises(IsADirectoryError) as caught:
        atomic_write_text(folder, "{}")
    assert caught.value.filename == str(folder)
    assert "folder" in str(caught.value)
    assert _names(tmp_path) == ["out.json"] and folder.is_dir()


def _drain(descriptor: int, expected: int, received: bytearray) -> None:
    """Read the non-blocking ``descriptor`` until ``expected`` bytes came, for 60 s at most; then
    close it, so that a writer blocked on a full pipe fails (EPIPE) instead of hanging the test."""
    deadline = time.monotonic() + 60
    try:
        while len(received) < expected and time.monotonic() < deadline:
            try:
                chunk = os.read(descriptor, 1 << 16)
            except BlockingIOError:
                chunk = b""
            if chunk:
                received.extend(chunk)
            else:
                time.sleep(0.005)  # no writer yet, or nothing written yet
    finally:
        os.close(descriptor)


@posix_only
def test_a_named_pipe_with_a_reader_receives_the_bytes_and_stays_a_pipe(tmp_path):
    pipe = tmp_path / "out.json"
    os.mkfifo(pipe)
    # Larger than a pipe's buffer (64 KiB on Linux): the save must wait for the reader, not fail.
    payload = bytes(range(256)) * 4096
    received = bytearray()
    reader = os.open(pipe, os.O_RDONLY | os.O_NONBLOCK)  # the reader is there before the save
    thread = threading.Thread(target=_drain, args=(reader, len(payload), received), daemon=True)
    thread.start()
    atomic_write_bytes(pipe, payload)
    thread.join(70)
    assert bytes(received) == payload
    assert stat.S_ISFIFO(os.stat(pipe).st_mode)
    assert _names(tmp_path) == ["out.json"]


@posix_only
def test_a_named_pipe_without_a_reader_fails_at_once_naming_it(tmp_path):
    # In a subprocess with a timeout: a save that waits for a reader must fail the test, not hang it.
    pipe = tmp_path / "out.json"
    os.mkfifo(pipe)
    code = textwrap.dedent(
        f"""
        from ursim_core.io.atomic import atomic_write_text
        try:
            atomic_write_text({str(pipe)!r}, "{{}}")
        except OSError as error:
            print(error.errno, error.filename, "|", error.strerror)
        """
    )
    started = time.monotonic()
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    numbers, _, problem = result.stdout.strip().partition(" | ")
    assert numbers.split() == [str(errno.ENXIO), str(pipe)]
    assert problem == "no process is reading the named pipe: nothing was written"
    assert time.monotonic() - started < 30
    assert stat.S_ISFIFO(os.stat(pipe).st_mode)
    assert _names(tmp_path) == ["out.json"]


@posix_only
def test_a_socket_is_refused(tmp_path):
    path = tmp_path / "s"
    if len(os.fsencode(path)) > 100:
        pytest.skip("the temporary folder's path is too long for a Unix socket")
    server = socket.socket(socket.AF_UNIX)
    try:
        server.bind(str(path))
        with pytest.raises(OSError, match="socket") as caught:
            atomic_write_text(path, "{}")
        assert caught.value.filename == str(path)
        assert stat.S_ISSOCK(os.stat(path).st_mode)
    finally:
        server.close()


def test_a_missing_folder_names_the_path_given_not_the_temporary_file(tmp_path):
    target = tmp_path / "nodir" / "w.yaml"
    with pytest.raises(FileNotFoundError) as caught:
        atomic_write_text(target, "waypoints: []\n")
    assert caught.value.filename == str(target)
    assert ".tmp" not in str(caught.value)
    assert "no folder" in str(caught.value)


def test_a_failed_rename_names_the_path_given(tmp_path, monkeypatch):
    target = tmp_path / "keep.json"

    def failing_replace(source, destination):
        raise OSError(errno.EROFS, "Read-only file system", str(source), str(destination))

    monkeypatch.setattr(os, "replace", failing_replace)
    with pytest.raises(OSError) as caught:
        atomic_write_bytes(target, b"x")
    assert caught.value.filename == str(target) and caught.value.filename2 is None
    assert ".tmp" not in str(caught.value)
    assert _names(tmp_path) == []


@pytest.mark.skipif(sys.platform == "win32", reason="RLIMIT_FSIZE")
def test_a_file_size_limit_names_the_file(tmp_path):
    # The ``ulimit -f`` of a shell: Python ignores SIGXFSZ at start-up, so the write fails with
    # EFBIG instead of the process being killed, and the error must say which file.
    target = tmp_path / "c.json"
    code = textwrap.dedent(
        f"""
        import resource, sys
        from ursim_core.io.atomic import atomic_write_bytes
        resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048))
        try:
            atomic_write_bytes({str(target)!r}, b"x" * 100_000)
        except OSError as error:
            print(error.errno, error.filename)
        """
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == [str(errno.EFBIG), str(target)]
    assert _names(tmp_path) == []
