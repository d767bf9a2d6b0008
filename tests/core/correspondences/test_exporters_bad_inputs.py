"""Exports (ursim_core.correspondences.exporters) of bad inputs: coordinates that are not finite
numbers (a georeference that overflows) and label images too large or cut, refused by name."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from image_files import png_header_only

from ursim_core.correspondences import Clique, Correspondences, MapRef, save_correspondences
from ursim_core.correspondences.exporters import export_correspondences, export_file, finite_json
from ursim_core.errors import FormatError, SegmentationError
from ursim_core.io.maps import load_map


def _map(folder, *, overflow: bool):
    image = np.zeros((40, 60), np.uint8)
    image[5:35, 5:55] = 255
    cv2.imwrite(str(folder / "map.png"), image)
    numbers = (
        "resolution: 1.0e+306\norigin: [1.7e+308, 1.7e+308, 0.0]" if overflow else "resolution: 0.05\norigin: [0, 0, 0]"
    )
    (folder / "map.yaml").write_text(f"image: map.png\n{numbers}\n")
    return folder / "map.yaml"


def _corr(sketch=None, metric=None):
    return Correspondences(
        sketch=sketch or MapRef(),
        metric=metric or MapRef(),
        cliques=(Clique(id=1, sketch_points=[(10, 20)], metric_points=[(12, 30)]),),
    )


def test_finite_json_names_the_first_field_that_is_not_a_number():
    assert finite_json({"a": [1, 2.5]}, "x.json") == '{"a": [1, 2.5]}'
    with pytest.raises(FormatError) as raised:
        finite_json({"a": [1.0, {"b": float("nan")}], "c": float("inf")}, "x.json")
    assert raised.value.field == "a[1].b" and str(raised.value.path) == "x.json"


@pytest.mark.parametrize("name", ["out.geojson", "out.points"])
def test_an_export_whose_georeference_overflows_is_refused_and_not_written(tmp_path, name):
    the_map = load_map(_map(tmp_path, overflow=True))
    target = tmp_path / name
    with np.errstate(all="raise"), pytest.raises(FormatError, match="not a finite number") as raised:
        export_correspondences(_corr(), target, the_map=the_map, metric_map=the_map)
    assert raised.value.path == target and "\n" not in str(raised.value)
    assert not target.exists()


def test_a_sane_georeference_still_exports(tmp_path):
    the_map = load_map(_map(tmp_path, overflow=False))
    export_correspondences(_corr(), tmp_path / "out.geojson", the_map=the_map, metric_map=the_map)
    export_correspondences(_corr(), tmp_path / "out.points", metric_map=the_map)
    assert "nan" not in (tmp_path / "out.points").read_text().lower()


def _file_with_labels(tmp_path, labels_path, size=(40, 60)):
    corr = _corr(metric=MapRef(size=size, labels_path=labels_path))
    source = tmp_path / "corr.json"
    save_correspondences(corr, source)
    return source


def test_a_label_image_whose_header_claims_too_many_pixels_is_refused_by_name(tmp_path):
    labels = png_header_only(tmp_path / "metric.labels.png", 100_000, 100_000)
    source = _file_with_labels(tmp_path, labels)
    with pytest.raises(SegmentationError, match="max_pixels") as raised:
        export_file(source, tmp_path / "out.geojson")
    assert raised.value.path == labels and not (tmp_path / "out.geojson").exists()


def test_a_cut_label_image_is_refused_by_name_without_an_opencv_warning(tmp_path, capfd):
    labels = tmp_path / "metric.labels.png"
    cv2.imwrite(str(labels), np.ones((40, 60), np.uint16))
    labels.write_bytes(labels.read_bytes()[:-30])
    source = _file_with_labels(tmp_path, labels)
    with pytest.raises(SegmentationError) as raised:
        export_file(source, tmp_path / "out.geojson")
    assert raised.value.path == labels and capfd.readouterr().err == ""


def test_a_good_16_bit_label_image_is_exported_as_before(tmp_path):
    values = np.zeros((40, 60), np.uint16)
    values[5:20, 5:30], values[20:35, 30:55] = 300, 7
    labels = tmp_path / "metric.labels.png"
    cv2.imwrite(str(labels), values)
    export_file(_file_with_labels(tmp_path, labels), tmp_path / "out.geojson")
    regions = (tmp_path / "out.geojson").read_text()
    assert '"region": 300' in regions and '"region": 7' in regions
