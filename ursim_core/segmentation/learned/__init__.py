"""Learned merging of candidate pieces: a third segmenter (``method="learned"``).

The map is over-segmented by overlaying MAORIS and the clearance watershed
(:mod:`~ursim_core.segmentation.learned.pieces`); a small classifier (boosted depth-2 trees,
:mod:`~ursim_core.segmentation.learned.model`, shipped as ``merge_model.json``) scores every
touching pair on features of its shared boundary, sizes and shapes
(:mod:`~ursim_core.segmentation.learned.features`), and pairs merge, the most probable
first, while the probability is at least 0.5 (:mod:`~ursim_core.segmentation.learned.merging`).
:mod:`~ursim_core.segmentation.learned.training` makes the training pairs from maps with
ground truth; ``tools/train_merging.py`` trains the shipped model and
:func:`ursim_core.segmentation.learned_cv.cross_validate_learned` gives its leave-one-map-out
figures.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["pieces", "features", "model", "merging", "training"],
    submod_attrs={
        "pieces": ["CandidatePieces", "candidate_pieces"],
        "features": ["FEATURE_NAMES", "PieceGraph"],
        "model": ["MergeModel", "fit_merge_model", "load_merge_model", "default_merge_model"],
        "merging": ["learned_labels", "agglomerate", "apply_merges", "resolve_learned_params", "LEARNED_DEFAULTS"],
        "training": ["oracle_pairs", "map_pairs", "train_merge_model"],
    },
)
