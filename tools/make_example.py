"""Regenerate the bundled example pair in resources/example, byte for byte.

    .venv/bin/python tools/make_example.py

The plan and the sketch come from one seed (``ursim_core.synth.make_pair``); the JSON
records a fixed timestamp so that running this again changes no file.
"""

from pathlib import Path

from ursim_core.synth import make_pair, save_example

SEED = 7
TIMESTAMP = "2026-11-22T00:00:00Z"
FOLDER = Path(__file__).resolve().parent.parent / "resources" / "example"

if __name__ == "__main__":
    plan, sketch = make_pair(seed=SEED)
    save_example(plan, sketch, FOLDER, now=TIMESTAMP)
    rooms = sum(place.kind == "room" for place in plan.places)
    print(
        f"wrote {FOLDER} (seed {SEED}): metric {plan.free.shape[0]} x {plan.free.shape[1]}, "
        f"{len(plan.places)} places ({rooms} rooms); sketch {sketch.free.shape[0]} x {sketch.free.shape[1]}"
    )
    for note in sketch.notes:
        print(f"  {note}")
