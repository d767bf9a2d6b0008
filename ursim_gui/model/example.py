"""The bundled example pair (resources/example) the app opens when started without inputs."""

from __future__ import annotations

from pathlib import Path

__all__ = ["EXAMPLE_DIR", "example_inputs"]

#: Folder of the bundled example: sketch.png, metric.png and ground_truth.json.
EXAMPLE_DIR = Path(__file__).resolve().parents[2] / "resources" / "example"


def example_inputs() -> tuple[Path, Path, Path | None] | None:
    """(sketch, metric, reference) of the bundled example, or None when it is missing."""
    sketch, metric = EXAMPLE_DIR / "sketch.png", EXAMPLE_DIR / "metric.png"
    if not (sketch.is_file() and metric.is_file()):
        return None
    reference = EXAMPLE_DIR / "ground_truth.json"
    return sketch, metric, reference if reference.is_file() else None
