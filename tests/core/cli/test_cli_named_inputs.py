"""An output never replaces a file that an input names (ursim_core.cli.inputs): the image of a ROS
map_server YAML map, or the maps and label images of a correspondence file. Each command refuses,
naming the output, the file it would destroy and the file that names it, and writes nothing."""

from __future__ import annotations

import hashlib

import cv2
import pytest
from cli_helpers import building, navigation_maps, rooms_image

from ursim_core.cli import main
from ursim_core.cli.inputs import correspondence_inputs, map_inputs, yaml_image
from ursim_core.correspondences import Clique, Correspondences, MapRef, save_correspondences


def _digests(folder):
    return {
        str(path.relative_to(folder)): hashlib.sha256(path.read_bytes()).hexdigest()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def _yaml(path, image: str):
    path.write_text(f"image: {image}\nresolution: 0.05\norigin: [-1.0, 2.0, 0.0]\n")
    return path


def _labelled_correspondences(folder, sketch, metric):
    """A correspondence file naming both maps and a label image of each (the metric one exists)."""
    cv2.imwrite(str(folder / "metric.labels.png"), rooms_image(width=90, height=70) // 255)
    corr = Correspondences(
        sketch=MapRef(path=sketch, labels_path=folder / "sketch.labels.png"),
        metric=MapRef(path=metric, labels_path=folder / "metric.labels.png"),
        cliques=(Clique(id=1, sketch_points=[(25, 30)], metric_points=[(35, 45)]),),
    )
    save_correspondences(corr, folder / "corr.json")
    return folder / "corr.json"


def _refused(err: str, output, destroyed, named_by) -> None:
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"error: {output}: refusing to write an output onto the input {destroyed} (")
    assert f"{named_by} names; it would be overwritten" in err


# ------------------------------------------------------------------------------ the YAML's image


def test_yaml_image_is_resolved_as_the_map_loader_resolves_it(tmp_path):
    (tmp_path / "maps").mkdir()
    relative = _yaml(tmp_path / "maps" / "a.yaml", "images/a.pgm")
    absolute = _yaml(tmp_path / "maps" / "b.YML", str(tmp_path / "b.pgm"))
    assert yaml_image(relative) == tmp_path / "maps" / "images" / "a.pgm"
    assert yaml_image(absolute) == tmp_path / "b.pgm"
    assert map_inputs(relative) == [(tmp_path / "maps" / "images" / "a.pgm", f"the image {relative} names")]


@pytest.mark.parametrize(
    "text",
    [
        "image: [a.pgm]\n",  # not a text
        "- image: a.pgm\n",  # not a mapping
        "image: 'a.pgm\n",  # not YAML
        "image: ''\n",
        "image: !!binary aGVsbG8=\n",
        "a: &x [*x]\nimage: *x\n",
    ],
)
def test_a_yaml_that_names_no_image_adds_no_input_and_never_raises(tmp_path, text):
    path = tmp_path / "map.yaml"
    path.write_text(text)
    assert map_inputs(path) == []
    assert map_inputs(tmp_path / "missing.yaml") == [] and map_inputs(tmp_path / "map.png") == []


def test_a_correspondence_file_names_its_maps_labels_and_yaml_images(tmp_path):
    sketch, _, metric_yaml = navigation_maps(tmp_path)
    corr_path = _labelled_correspondences(tmp_path, sketch, metric_yaml)
    from ursim_core.correspondences import load_correspondences

    named = dict(correspondence_inputs(corr_path, load_correspondences(corr_path)))
    assert named == {
        sketch: f"the sketch map {corr_path} names",
        tmp_path / "sketch.labels.png": f"the sketch label image {corr_path} names",
        metric_yaml: f"the metric map {corr_path} names",
        tmp_path / "metric.pgm": f"the image {metric_yaml} names",
        tmp_path / "metric.labels.png": f"the metric label image {corr_path} names",
    }


# --------------------------------------------------------------------------------- per command


def test_match_refuses_an_output_onto_the_image_of_a_yaml_map(tmp_path, capsys):
    # The metric map's image is where `ursim match -o out` writes the metric labels.
    out = tmp_path / "out"
    out.mkdir()
    cv2.imwrite(str(tmp_path / "sketch.png"), building(1.3))
    cv2.imwrite(str(out / "metric.labels.png"), building())
    metric = _yaml(tmp_path / "metric.yaml", "out/metric.labels.png")
    before = _digests(tmp_path)
    assert main(["match", str(tmp_path / "sketch.png"), str(metric), "-o", str(out)]) == 1
    _refused(capsys.readouterr().err, out / "metric.labels.png", out / "metric.labels.png", metric)
    assert _digests(tmp_path) == before


def test_segment_refuses_an_output_onto_the_image_of_a_yaml_map(tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    cv2.imwrite(str(out / "room.overlay.png"), rooms_image())
    room = _yaml(out / "room.yaml", "room.overlay.png")
    before = _digests(tmp_path)
    assert main(["segment", str(room), "-o", str(out)]) == 1
    _refused(capsys.readouterr().err, out / "room.overlay.png", out / "room.overlay.png", room)
    assert _digests(tmp_path) == before


def test_goal_refuses_an_output_onto_a_yaml_image_or_a_label_image_of_its_correspondences(tmp_path, capsys):
    sketch, _, metric_yaml = navigation_maps(tmp_path)
    corr = _labelled_correspondences(tmp_path, sketch, metric_yaml)
    before = _digests(tmp_path)
    base = ["goal", str(sketch), str(metric_yaml), "--at", "25,30"]
    assert main([*base, "-o", str(tmp_path / "metric.pgm")]) == 1
    _refused(capsys.readouterr().err, tmp_path / "metric.pgm", tmp_path / "metric.pgm", metric_yaml)
    assert main([*base, "--correspondences", str(corr), "-o", str(tmp_path / "metric.labels.png")]) == 1
    labels = tmp_path / "metric.labels.png"
    _refused(capsys.readouterr().err, labels, labels, f"the metric label image {corr}")
    assert _digests(tmp_path) == before


def test_route_refuses_an_output_onto_a_map_its_correspondences_name(tmp_path, capsys):
    # The file names the PNG of the map the route runs on as a YAML: its waypoints must not replace it.
    sketch, metric_png, metric_yaml = navigation_maps(tmp_path)
    corr = _labelled_correspondences(tmp_path, sketch, metric_png)
    points = tmp_path / "route.txt"
    points.write_text("25,20\n25,180\n")
    before = _digests(tmp_path)
    argv = ["route", str(sketch), str(metric_yaml), "--points", str(points), "--correspondences", str(corr)]
    assert main([*argv, "--waypoints", str(metric_png)]) == 1
    _refused(capsys.readouterr().err, metric_png, metric_png, f"the metric map {corr}")
    assert main([*argv, "-o", str(tmp_path / "metric.pgm")]) == 1
    _refused(capsys.readouterr().err, tmp_path / "metric.pgm", tmp_path / "metric.pgm", metric_yaml)
    assert _digests(tmp_path) == before


def test_convert_refuses_an_export_onto_the_image_of_a_yaml_map_its_file_names(tmp_path, capsys):
    sketch, _, metric_yaml = navigation_maps(tmp_path)
    corr = _labelled_correspondences(tmp_path, sketch, metric_yaml)
    before = _digests(tmp_path)
    target = tmp_path / "metric.pgm"
    assert main(["convert", str(corr), str(target), "--format", "geojson"]) == 1
    _refused(capsys.readouterr().err, target, target, metric_yaml)
    assert _digests(tmp_path) == before


def test_the_commands_still_write_beside_the_files_their_inputs_name(tmp_path, capsys):
    sketch, _, metric_yaml = navigation_maps(tmp_path)
    corr = _labelled_correspondences(tmp_path, sketch, metric_yaml)
    assert main(["convert", str(corr), str(tmp_path / "regions.geojson")]) == 0
    argv = ["goal", str(sketch), str(metric_yaml), "--at", "25,30", "--correspondences", str(corr)]
    assert main([*argv, "-o", str(tmp_path / "goal.json")]) == 0
    assert (tmp_path / "regions.geojson").is_file() and (tmp_path / "goal.json").is_file()
