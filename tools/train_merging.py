"""Train the merge model of the learned segmenter and write it into the package.

    .venv/bin/python tools/train_merging.py [--datasets DIR] [--out FILE]
    .venv/bin/python tools/train_merging.py --cv [--datasets DIR]   # figures only, writes nothing

Trains on all 18 sketches of ``maoris_segmentation`` and both annotators' ground truth
(:func:`ursim_core.segmentation.learned.training.map_pairs`), with the boosting settings of
:data:`~ursim_core.segmentation.learned.training.TRAINING_DEFAULTS`, and writes
``ursim_core/segmentation/learned/merge_model.json``. Training is deterministic: running it
again on the same data writes the same bytes. ``--cv`` prints its leave-one-map-out figures
(:func:`ursim_core.segmentation.learned_cv.cross_validate_learned`) per map and annotator,
beside those of the MAORIS ``sketch`` preset (:func:`ursim_core.segmentation.presets_cv.cross_validate`).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ursim_core.errors import UrsimError
from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root
from ursim_core.segmentation.learned.merging import LEARNED_DEFAULTS
from ursim_core.segmentation.learned.pieces import candidate_pieces
from ursim_core.segmentation.learned.training import TRAINING_DEFAULTS, map_pairs, train_merge_model
from ursim_core.segmentation.presets_cv import load_benchmark

OUT = Path(__file__).resolve().parent.parent / "ursim_core" / "segmentation" / "learned" / "merge_model.json"
PIECES = {k: LEARNED_DEFAULTS[k] for k in ("maoris_preset", "door_ratio", "watershed_min_size", "min_piece")}

PROVENANCE = {
    "trained_on": "maoris_segmentation/sketches: the 18 KTH sketch maps (maps/NN.png) with the segmentation "
    "ground truth of two annotators (gt_lex/NN.png, gt_ezvin/NN.png)",
    "source": "https://github.com/MalcolmMielle/maoris (Test/Sketches), commit 78a2e5287cc24069060e1d989fd8692c060d29e2; "
    "Mielle, Magnusson, Lilienthal, 'A method to segment maps from different modalities using free space layout - "
    "MAORIS: MAp Of RIpples Segmentation', ICRA 2018",
    "licence": "GPL-3.0 (the licence of the source repository; no separate data licence is given). This model is "
    "derived from that data and is distributed under the same terms.",
}


def print_cross_validation(root: Path) -> None:
    """Per map and annotator, then mean and worst: learned merging beside the ``sketch`` preset."""
    from ursim_core.segmentation.learned_cv import cross_validate_learned
    from ursim_core.segmentation.presets_cv import cross_validate, default_selections

    benchmark = load_benchmark(root, "sketches")
    learned = cross_validate_learned(benchmark)
    preset = cross_validate(benchmark=benchmark, selections={"sketch": default_selections()["sketch"]}, fixed={})
    cv = {(r["preset"], r["map"], r["annotator"]): r["cv_f1"] for r in learned.rows + preset.rows}
    annotators = list(benchmark[0].ground_truths)
    print("leave-one-map-out F1 (learned: model trained without the map; sketch: preset chosen without it)")
    print("map  " + "  ".join(f"{a + ' sketch':>15} {a + ' learned':>16}" for a in annotators))
    for item in benchmark:
        cells = [f"{cv[('sketch', item.name, a)]:15.3f} {cv[('learned', item.name, a)]:16.3f}" for a in annotators]
        print(f"{item.name:4} " + "  ".join(cells))
    for row in preset.summary() + learned.summary():
        print(
            f"{row['preset']:22} {row['annotator']:10} cv mean {row['cv_mean']:.3f} worst {row['cv_worst']:.3f}"
            f"   in-sample mean {row['in_sample_mean']:.3f}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--datasets", help="the shared datasets folder (default: $URSIM_DATASETS or ../shared/datasets)"
    )
    parser.add_argument("--out", type=Path, default=OUT, help=f"model file to write (default: {OUT})")
    parser.add_argument("--cv", action="store_true", help="print leave-one-map-out figures instead of training")
    args = parser.parse_args(argv)
    root = dataset_root(args.datasets)
    if root is None:
        print(MISSING_REASON, file=sys.stderr)
        return 1
    if args.cv:
        print_cross_validation(root)
        return 0
    try:
        benchmark = load_benchmark(root, "sketches")
        samples = [map_pairs(candidate_pieces(item.free, **PIECES), item.ground_truths) for item in benchmark]
        metadata = {
            **PROVENANCE,
            "maps": [item.name for item in benchmark],
            "pairs": int(sum(len(s[1]) for s in samples)),
            "candidate_pieces": PIECES,
            "training": TRAINING_DEFAULTS,
            "trainer": "tools/train_merging.py (ursim_core.segmentation.learned.model.fit_merge_model)",
        }
        model = train_merge_model(samples, metadata=metadata)
        model.save(args.out)
    except UrsimError as error:
        print(error, file=sys.stderr)
        return 1
    print(f"wrote {args.out}: {len(model.leaf)} trees over {len(model.features)} features, {metadata['pairs']} pairs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
