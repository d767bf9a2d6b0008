"""Scoring matches against ground truth and running the paper's experiments.

Owns: pair scores (:mod:`~ursim_core.evaluation.scoring`), place accuracy
(:mod:`~ursim_core.evaluation.place`), both for one match against a file
(:mod:`~ursim_core.evaluation.match_scores`), the dataset
layouts and where the datasets are (:mod:`~ursim_core.evaluation.layouts`,
:mod:`~ursim_core.evaluation.datasets`), the experiment runner behind ``ursim evaluate``
(:mod:`~ursim_core.evaluation.runner`, with its segmentation cache :mod:`~ursim_core.evaluation.cache`,
process pool :mod:`~ursim_core.evaluation.pool` and scored tasks :mod:`~ursim_core.evaluation.tasks`),
the values it produces and their summaries (:mod:`~ursim_core.evaluation.results`), the ceiling of a
one-to-one matcher against the annotators (:mod:`~ursim_core.evaluation.ceiling`), the KTH protocol
of the matching benchmark (:mod:`~ursim_core.evaluation.kth_protocol`), turned and mirrored
sketches with their ground truth (:mod:`~ursim_core.evaluation.augment`), a simulated annotator's
review (:mod:`~ursim_core.evaluation.review`) and the report
(:mod:`~ursim_core.evaluation.report`: CSV and markdown; :mod:`~ursim_core.evaluation.tables`,
:mod:`~ursim_core.evaluation.plots`, :mod:`~ursim_core.evaluation.published`).

May import: :mod:`ursim_core.matching`, :mod:`ursim_core.segmentation`,
:mod:`ursim_core.correspondences`, :mod:`ursim_core.io`, :mod:`ursim_core.errors`.
"""

import lazy_loader as _lazy

__getattr__, __dir__, __all__ = _lazy.attach(
    __name__,
    submodules=[
        "augment",
        "cache",
        "ceiling",
        "datasets",
        "formatting",
        "kth_protocol",
        "layouts",
        "match_scores",
        "place",
        "plots",
        "pool",
        "published",
        "report",
        "results",
        "review",
        "runner",
        "scoring",
        "tables",
        "tasks",
    ],
    submod_attrs={
        "scoring": [
            "MatchScore",
            "score_matches",
            "score_cliques",
            "SCORING_MODES",
        ],
        "place": ["PLACE_REFERENCE_PRESET", "PlaceScore", "place_accuracy"],
        "ceiling": ["Ceiling", "best_one_to_one"],
        "match_scores": ["MatchScores", "score_against_reference"],
        "augment": ["Orientation", "DIHEDRAL", "parse_augment", "transform_image", "transform_points"],
        "layouts": ["Experiment", "discover"],
        "datasets": ["dataset_root", "DATASET_ENV", "MISSING_REASON"],
        "results": [
            "DEFAULT_M_GRID",
            "MATCHERS",
            "VARIANTS",
            "POOLED",
            "RUN_COLUMNS",
            "RunRow",
            "Summary",
            "EvaluationResult",
            "summarise",
            "summarise_human",
            "mean_f1_by_m",
            "m_label",
        ],
        "runner": ["run_evaluation"],
        "tables": ["format_tables"],
        "report": ["write_report", "runs_csv", "markdown_summary"],
        "plots": ["plot_f1_vs_m", "plot_boxplots"],
    },
)
