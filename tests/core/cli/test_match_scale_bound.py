"""``ursim match`` with a scale (given, or from two ROS maps' resolutions) too large to place the
input: one line naming the scale, exit 1, nothing written (it crashed OpenCV)."""

from __future__ import annotations

import cv2
from cli_helpers import building

from ursim_core.cli import main


def _yaml(folder, name: str, resolution: float):
    (folder / f"{name}.yaml").write_text(
        f"image: {name}.png\nresolution: {resolution}\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    return folder / f"{name}.yaml"


def test_a_given_scale_too_large_is_one_line_naming_it(tmp_path, capsys):
    cv2.imwrite(str(tmp_path / "map.png"), building())
    out = tmp_path / "out"
    code = main(["match", str(tmp_path / "map.png"), str(tmp_path / "map.png"), "-o", str(out), "--scale", "100"])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("error: ") and "scale 100" in err and len(err.strip().splitlines()) == 1
    assert not out.exists() and not list(tmp_path.glob(".out.*"))


def test_two_ros_maps_whose_resolutions_give_such_a_scale_are_refused(tmp_path, capsys):
    cv2.imwrite(str(tmp_path / "a.png"), building())
    cv2.imwrite(str(tmp_path / "b.png"), building())
    sketch, metric = _yaml(tmp_path, "a", 5.0), _yaml(tmp_path, "b", 0.05)
    code = main(["match", str(sketch), str(metric), "-o", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 1 and "scale 100" in err and "resolution" in err and len(err.strip().splitlines()) == 1
