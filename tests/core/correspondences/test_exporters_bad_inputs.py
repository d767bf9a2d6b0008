"""Exports (ursim_core.correspondences.exporters) of bad inputs: coordinates that are not finite
numbers (a georeference that overflows) and label images too large or cut, refused by name."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from image_files import png_header_only

from ursim_core.correspondences import Clique, Correspondences, MapRef, save_correspondences
from ursim_core.correspondences.exporters import export_correspondences, export_file
from ursim_core.correspondences.json_text import finite_json
from ursim_core.errors import FormatError, SegmentationError
from ursim_core.io.maps import Map, load_map


def _map(folder):
    image = np.zeros((40, 60), np.uint8)
    image[5:35, 5:55] = 255
    cv2.imwrite(str(folder / "map.png"), image)
    (folder / "map.yaml").write_text("image: map.png\nresolution: 0.05\norigin: [0, 0, 0]\n")
    return folder / "map.yaml"


def _overflowing_map():
    # The loaders refuse such a georeference (test_ros_yaml); a Map built in code can still hold
    # one, and the writers are the last line.
    free = np.zeros((40, 60), bool)
    free[5:35, 5:55] = True
    return Map(free=free, resolution=1.0e306, origin=(1.7e308, 1.7e308, 0.0))


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
    the_map = _overflowing_map()
    target = tmp_path / name
    with np.errstate(all="raise"), pytest.raises(FormatError, match="not a finite number") as raised:
        export_correspondences(_corr(), target, the_map=the_map, metric_map=the_map)
    assert raised.value.path == target and "\n" not in str(raised.value)
    assert not target.exists()


def test_a_sane_georeference_still_exports(tmp_path):
    the_map = load_map(_map(tmp_path))
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


def test_a_label_image_the_app_reads_is_exported_too(tmp_path):
    # A grey label image saved as RGB by another tool loads in the app (equal channels); the
    # export read it with a reader of its own that refused it.
    values = np.zeros((40, 60), np.uint8)
    values[5:20, 5:30], values[20:35, 30:55] = 3, 7
    labels = tmp_path / "metric.labels.png"
    cv2.imwrite(str(labels), np.dstack([values] * 3))
    export_file(_file_with_labels(tmp_path, labels), tmp_path / "out.geojson")
    regions = (tmp_path / "out.geojson").read_text()
    assert '"region": 3' in regions and '"region": 7' in regions
    cv2.imwrite(str(labels), np.dstack([values, values, values + 1]))
    with pytest.raises(SegmentationError, match="one channel") as raised:
        export_file(_file_with_labels(tmp_path, labels), tmp_path / "other.geojson")
    assert raised.value.path == labels and not (tmp_path / "other.geojson").exists()
