"""Map files read ahead on a thread (ursim_gui.model.read_ahead): used only while unchanged."""

from __future__ import annotations

import os
import threading

import cv2
import numpy as np
import pytest

from ursim_core.errors import MapError
from ursim_core.io.maps import load_map
from ursim_gui.model.read_ahead import MapReadAhead


def _image(path, value=255, shape=(20, 30)):
    image = np.zeros(shape, np.uint8)
    image[2:-2, 2:-2] = value
    cv2.imwrite(str(path), image)
    return path


def _recording():
    threads: list[str] = []

    def load(path):
        threads.append(threading.current_thread().name)
        return load_map(path)

    return threads, load


def test_a_map_read_ahead_is_read_on_the_thread_and_handed_over(tmp_path):
    path = _image(tmp_path / "a.png")
    threads, load = _recording()
    ahead = MapReadAhead(load)
    ahead.prefetch([path, path])
    map_ = ahead.read(path)
    assert map_.shape == (20, 30) and np.array_equal(map_.free, load_map(path).free)
    assert len(threads) == 1 and threads[0].startswith("ursim-read-ahead")
    assert ahead.pending == ()
    ahead.read(path)  # taken once: read again, here
    assert threads[-1] == threading.current_thread().name
    ahead.close()


def test_a_file_changed_after_it_was_read_ahead_is_read_again(tmp_path):
    path = _image(tmp_path / "a.png")
    ahead = MapReadAhead()
    ahead.prefetch([path])
    ahead._reads[path.absolute()].result()  # the read ahead is done
    _image(path, shape=(24, 30))
    stamp = os.stat(path)
    os.utime(path, ns=(stamp.st_atime_ns, stamp.st_mtime_ns + 1_000_000))
    assert ahead.read(path).shape == (24, 30)
    ahead.close()


def test_a_file_that_fails_ahead_fails_again_with_its_own_error(tmp_path):
    path = tmp_path / "broken.png"
    path.write_bytes(b"not an image")
    ahead = MapReadAhead()
    ahead.prefetch([path])
    with pytest.raises(MapError, match="broken.png"):
        ahead.read(path)
    ahead.close()


def test_asking_for_other_files_drops_the_reads_not_taken(tmp_path):
    a, b = _image(tmp_path / "a.png"), _image(tmp_path / "b.png")
    ahead = MapReadAhead()
    ahead.prefetch([a, b])
    ahead.prefetch([b])
    assert ahead.pending == (b.absolute(),)
    ahead.close()
    assert ahead.pending == ()
    assert ahead.read(a).shape == (20, 30)  # closed, it still reads, on the caller's thread
