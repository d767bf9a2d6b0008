"""The files a command reads beyond those on its command line, for its overwrite check.

A ROS map_server YAML map is read with the image it names, and a correspondence file names its
two maps and their label images: an output written onto one of them destroys an input as surely
as one written onto an argument (``ursim goal sketch.png map.yaml --at 1,2 -o map.pgm`` would
turn the robot's map into JSON). Each function returns ``(path, why)`` pairs, which
:func:`ursim_core.cli.common.refuse_overwriting_inputs` takes beside plain paths and names in its
message.

Nothing here raises: a file that cannot be read adds nothing, and the command reports its
problem when it loads it.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["map_inputs", "yaml_image", "correspondence_inputs"]

#: A file read, and why (for the message).
DescribedInput = tuple[Path, str]


def map_inputs(path: str | os.PathLike | None) -> list[DescribedInput]:
    """The image a map argument ``path`` names when it is a ROS map_server YAML file, as a
    ``(path, why)`` pair; nothing for an image or a YAML that cannot be read.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> folder = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (folder / "map.yaml").write_text("image: map.pgm\\nresolution: 0.05\\norigin: [0, 0, 0]\\n")
    >>> [(image.name, why.startswith("the image")) for image, why in map_inputs(folder / "map.yaml")]
    [('map.pgm', True)]
    >>> map_inputs(folder / "map.png")
    []
    """
    if path is None:
        return []
    image = yaml_image(path)
    return [] if image is None else [(image, f"the image {path} names")]


def yaml_image(path: str | os.PathLike) -> Path | None:
    """The image a ROS map_server YAML file names (:func:`ursim_core.io.ros_yaml.ros_image_path`,
    the loader's rule), or None when ``path`` has no ``.yaml``/``.yml`` suffix or cannot be read
    as a map_server file (the command says why when it loads it)."""
    from ursim_core.errors import MapError
    from ursim_core.io.ros_yaml import ROS_SUFFIXES, ros_image_path

    if Path(path).suffix.lower() not in ROS_SUFFIXES:
        return None
    try:
        return ros_image_path(path)
    except MapError:
        return None


def correspondence_inputs(path: str | os.PathLike | None, corr) -> list[DescribedInput]:
    """The maps and label images the correspondence file ``path`` (loaded as ``corr``) names, and
    the images of those maps that are ROS YAML files, as ``(path, why)`` pairs.

    Exports and navigation read them; and even one a command does not read belongs to the file,
    which would point at a destroyed map (the rule of the correspondence savers).
    """
    if path is None or corr is None:
        return []
    found: list[DescribedInput] = []
    for side, ref in (("sketch", corr.sketch), ("metric", corr.metric)):
        if ref.path is not None:
            found.append((Path(ref.path), f"the {side} map {path} names"))
            found.extend(map_inputs(ref.path))
        if ref.labels_path is not None:
            found.append((Path(ref.labels_path), f"the {side} label image {path} names"))
    return found
