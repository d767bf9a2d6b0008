"""The learned segmenter's model file (ursim_core.segmentation.learned.model.load_merge_model) is read
as every input is: a regular file of bounded size, JSON guarded against nesting and huge numbers."""

from __future__ import annotations

import json
import os
import sys
import threading

import pytest

from ursim_core.errors import SegmentationError
from ursim_core.segmentation.learned.model import default_merge_model, load_merge_model


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("[" * 100_000 + "]" * 100_000, "nested deeper than"),
        ('{"format": "ursim-merge-model", "version": 1, "base": ' + "9" * 5000 + "}", "5000 digits"),
        ('{"format": "ursim-merge-model", "version": 1, "base": ' + "9" * 400 + "}", "400 digits"),
        ('{"format": "ursim-merge-model", "version": 1, "base": NaN}', "NaN"),
        ("", "empty file"),
    ],
)
def test_a_model_file_json_cannot_hold_is_a_segmentation_error(tmp_path, text, problem):
    path = tmp_path / "model.json"
    path.write_text(text)
    with pytest.raises(SegmentationError, match=problem) as caught:
        load_merge_model(path)
    assert str(caught.value).startswith(f"{path}: ")


@pytest.mark.skipif(sys.platform == "win32", reason="named pipes")
def test_a_named_pipe_is_refused_without_opening_it(tmp_path):
    pipe = tmp_path / "model.json"
    os.mkfifo(pipe)
    outcome: dict = {}

    def load():
        try:
            load_merge_model(pipe)
        except BaseException as error:
            outcome["error"] = error

    thread = threading.Thread(target=load, daemon=True)
    thread.start()
    thread.join(20)
    if thread.is_alive():
        # Give the reader blocked in open() a writer and an end of file, so the run goes on.
        os.close(os.open(pipe, os.O_WRONLY | os.O_NONBLOCK))
        thread.join(5)
        pytest.fail("blocked reading the named pipe")
    assert isinstance(outcome.get("error"), SegmentationError) and "named pipe" in str(outcome["error"])


def test_a_model_with_a_byte_order_mark_loads_and_saves_again(tmp_path):
    path = tmp_path / "model.json"
    path.write_bytes(b"\xef\xbb\xbf" + json.dumps(default_merge_model().to_dict()).encode())
    model = load_merge_model(path)
    model.save(tmp_path / "again.json")
    assert load_merge_model(tmp_path / "again.json").to_dict() == default_merge_model().to_dict()
