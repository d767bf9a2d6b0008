"""Scoring matches against ground truth and running the paper's experiments.

Owns: pair scores and place accuracy (:mod:`~ursim_core.evaluation.scoring`), the dataset
layouts and where the datasets are (:mod:`~ursim_core.evaluation.layouts`,
:mod:`~ursim_core.evaluation.datasets`), the experiment runner behind ``ursim evaluate``
(:mod:`~ursim_core.evaluation.runner`), the KTH protocol of the matching benchmark
(:mod:`~ursim_core.evaluation.kth_protocol`) and the report (tables, CSV, plots).

May import: :mod:`ursim_core.matching`, :mod:`ursim_core.segmentation`,
:mod:`ursim_core.correspondences`, :mod:`ursim_core.io`, :mod:`ursim_core.errors`.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=["datasets", "kth_protocol", "layouts", "report", "runner", "scoring"],
    submod_attrs={
        "scoring": ["MatchScore", "score_matches", "score_cliques", "SCORING_MODES"],
        "layouts": ["Experiment", "discover"],
        "datasets": ["dataset_root", "DATASET_ENV", "MISSING_REASON"],
        "runner": [
            "RunRow",
            "Summary",
            "EvaluationResult",
            "run_evaluation",
            "summarise",
            "summarise_human",
            "mean_f1_by_m",
            "m_label",
            "format_tables",
            "write_report",
        ],
    },
)
