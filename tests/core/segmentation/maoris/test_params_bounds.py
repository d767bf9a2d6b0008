"""MAORIS size parameters have a maximum (ursim_core.segmentation.maoris.params): a huge value is a
ParameterError naming it and its range, never an OverflowError in the kernels."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from ursim_core.cli import main
from ursim_core.errors import ParameterError
from ursim_core.segmentation.maoris.params import MaorisParams


@pytest.mark.parametrize("name", ["small_before", "small_after", "max_radius"])
@pytest.mark.parametrize("value", [10**20, 1e300, 2**63 - 1, 10**400])
def test_a_size_past_the_maximum_is_refused_by_name(name, value):
    with pytest.raises(ParameterError, match=r"<= 9007199254740992") as raised:
        MaorisParams(**{name: value})
    assert raised.value.field == name


def test_the_maximum_itself_is_accepted():
    params = MaorisParams(small_before=2**53, small_after=2**53, max_radius=2**53)
    assert params.small_before == params.small_after == params.max_radius == 2**53
    with pytest.raises(ParameterError, match="integer"):
        MaorisParams(small_before=1.5)
    with pytest.raises(ParameterError, match=">= 0.0 and < 1.0"):
        MaorisParams(threshold=10**400)


def test_segment_with_a_huge_size_is_one_line(tmp_path, capsys):
    image = np.zeros((40, 60), np.uint8)
    image[5:35, 5:55] = 255
    cv2.imwrite(str(tmp_path / "map.png"), image)
    code = main(["segment", str(tmp_path / "map.png"), "-o", str(tmp_path / "out"), "--param", "small_before=1e20"])
    err = capsys.readouterr().err
    assert code == 1 and "small_before" in err and len(err.strip().splitlines()) == 1
