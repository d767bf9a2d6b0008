"""Regenerate the bundled example pair in resources/example (deterministic).

    .venv/bin/python tools/make_example.py
"""

from pathlib import Path

from ursim_core.synth import make_pair, save_example

SEED = 7
FOLDER = Path(__file__).resolve().parent.parent / "resources" / "example"

if __name__ == "__main__":
    plan, sketch = make_pair(seed=SEED)
    save_example(plan, sketch, FOLDER)
    print(f"wrote {FOLDER} (seed {SEED}: {len(plan.kinds)} places, sketch drops {sketch.dropped}, adds {sketch.extra})")
