"""The experiment runner (ursim_core.evaluation.runner) on the synthetic dataset of conftest.py and on real data."""

from __future__ import annotations

import math

import pytest
from PIL import Image
from synthetic_kth import SKETCH_SCALES, plan_image

from ursim_core.errors import ParameterError
from ursim_core.evaluation import report, tables
from ursim_core.evaluation.results import DEFAULT_M_GRID, EvaluationResult
from ursim_core.evaluation.runner import run_evaluation

GRID = (0.0, 0.1, 0.2)


@pytest.fixture(scope="module")
def synthetic_result(synthetic_dataset) -> EvaluationResult:
    return run_evaluation(
        synthetic_dataset,
        matchers=["planar", "hungarian"],
        variants=["T4", "baseline"],
        m_grid=GRID,
        preset="robot",
        metric_preset="robot",
        workers=1,
    )


def test_runner_produces_one_row_per_map_annotator_matcher_variant_and_m(synthetic_result):
    rows = synthetic_result.rows
    assert len(rows) == 2 * 2 * 2 * 2 * (len(GRID) + 1)
    keys = {(r.map, r.annotator, r.matcher, r.variant, r.m_label) for r in rows}
    assert len(keys) == len(rows)
    assert {r.m_label for r in rows} == {"0", "0.1", "0.2", "auto"}
    for row in rows:
        assert 0.0 <= row.f1 <= 1.0 and row.scoring == "correct"
        assert row.n_sketch_regions == 3 and row.n_metric_regions == 3
        assert row.model == "model/model_simple" and row.time_s >= 0
        if row.m_label != "auto":
            assert row.m_value == float(row.m_label)
        if row.tp:
            assert row.f1 == pytest.approx(2 * row.precision * row.recall / (row.precision + row.recall))


def test_runner_matches_an_identical_map_perfectly(synthetic_result):
    # The "copy" sketch is the model itself: the oracle m must recover every room.
    oracle = synthetic_result.summary("malcolm", "planar", "T4", "oracle")
    assert dict(zip(oracle.maps, oracle.f1))["copy"] == 1.0
    copy_rows = [
        r
        for r in synthetic_result.rows
        if r.map == "copy" and r.annotator == "malcolm" and r.matcher == "planar" and r.variant == "T4" and r.f1 == 1.0
    ]
    assert all((r.tp, r.fp, r.fn) == (3, 0, 0) for r in copy_rows)


def test_human_vs_human_has_the_known_answer(synthetic_result):
    # vasiliki's two cliques are two of malcolm's three: scored against malcolm, P = 1, R = 2/3;
    # malcolm's against vasiliki's, P = 2/3, R = 1. F1 = 0.8 both ways, on both maps.
    human = {(r.map, r.annotator, r.variant): r for r in synthetic_result.human_rows}
    assert set(human) == {
        (m, a, b) for m in SKETCH_SCALES for a, b in (("malcolm", "vasiliki"), ("vasiliki", "malcolm"))
    }
    for (_name, reference, _scored), row in human.items():
        assert row.f1 == pytest.approx(0.8)
        if reference == "malcolm":
            assert (row.tp, row.fp, row.fn) == (2, 0, 1)
        else:
            assert (row.tp, row.fp, row.fn) == (2, 1, 0)
    assert all(s.mean == pytest.approx(0.8) for s in synthetic_result.human_summaries)


def test_runner_settings_and_timings(synthetic_result, synthetic_dataset):
    settings = synthetic_result.settings
    assert settings["matchers"] == ["planar", "hungarian"] and settings["variants"] == ["T4", "baseline"]
    assert settings["m_grid"] == list(GRID) and settings["scoring"] == "correct"
    assert settings["presets_used"] == ["robot"]
    assert settings["dataset"] == str(synthetic_dataset)
    # sketches/copy.png has the model's bytes, but a sketch is segmented in its canonical pose
    # (its orientation is unknown to the default matcher) and the model as it is: two jobs; the
    # model once more with the 'default' preset, the reference segmentation of place accuracy.
    assert synthetic_result.timings["maps"] == 4
    assert settings["place_reference_preset"] == "default" and settings["augment"] == []
    assert synthetic_result.notes == ()


def test_legacy_scoring_modes(synthetic_dataset):
    as_built = run_evaluation(
        synthetic_dataset,
        matchers=["planar"],
        variants=["T4"],
        m_grid=(0.1,),
        preset="robot",
        workers=1,
        legacy_scoring=True,
        human=False,
        auto_m=False,
    )
    assert {r.scoring for r in as_built.rows} == {"as-built"} and {r.fn for r in as_built.rows} == {0}
    assert as_built.human_rows == ()
    fnfix = run_evaluation(
        synthetic_dataset,
        matchers=["planar"],
        variants=["T4"],
        m_grid=(0.1,),
        preset="robot",
        workers=1,
        legacy_scoring="fnfix",
        auto_m=False,
    )
    # The trailing empty match set can never be hit: at least one FN everywhere.
    assert all(r.fn >= 1 for r in fnfix.rows)
    assert {r.m_label for r in fnfix.rows} == {"0.1"}


def test_progress_counts_every_step_and_caches_are_used(synthetic_dataset, tmp_path):
    calls = []
    cache: dict = {}
    options = dict(
        matchers=["hungarian"],
        variants=["T1", "T2"],
        m_grid=(0.1,),
        preset="robot",
        metric_preset="robot",
        workers=1,
        segmentation_cache=cache,
        cache_dir=tmp_path / "segcache",
    )
    first = run_evaluation(
        synthetic_dataset, progress=lambda done, total, text: calls.append((done, total, text)), **options
    )
    # distinct maps (the sketch with the model's bytes is segmented in its canonical pose, the model as
    # it is; + the model's place-accuracy reference) + (experiment x variant) tasks + human vs human
    total = 4 + 2 * 2 + 1
    assert [c[0] for c in calls] == list(range(1, total + 1)) and {c[1] for c in calls} == {total}
    assert any(text.startswith("segment") for _, _, text in calls) and calls[-1][2] == "human vs human"
    assert first.timings["maps_from_cache"] == 0 and len(cache) == 4
    assert len(list((tmp_path / "segcache").glob("*.npz"))) == 4

    in_memory = run_evaluation(synthetic_dataset, **options)
    assert in_memory.timings["maps_from_cache"] == 4
    on_disk = run_evaluation(synthetic_dataset, **{**options, "segmentation_cache": None})
    assert on_disk.timings["maps_from_cache"] == 4
    assert [r.f1 for r in on_disk.rows] == [r.f1 for r in first.rows]


def test_two_worker_processes_give_the_same_rows(synthetic_dataset, synthetic_result):
    parallel = run_evaluation(
        synthetic_dataset,
        matchers=["planar", "hungarian"],
        variants=["T4", "baseline"],
        m_grid=GRID,
        preset="robot",
        workers=2,
    )
    strip = lambda rows: [(r.map, r.annotator, r.matcher, r.variant, r.m_label, r.tp, r.fp, r.fn, r.f1) for r in rows]
    assert strip(parallel.rows) == strip(synthetic_result.rows)


def test_map_selection_and_experiment_list(synthetic_dataset):
    from ursim_core.evaluation.layouts import discover

    only_copy = run_evaluation(
        synthetic_dataset,
        matchers=["hungarian"],
        variants=["T1"],
        m_grid=(0.1,),
        preset="robot",
        workers=1,
        maps=["copy"],
        auto_m=False,
    )
    assert {r.map for r in only_copy.rows} == {"copy"}
    experiments = [e for e in discover(synthetic_dataset) if e.name == "small"]
    given = run_evaluation(
        experiments, matchers=["hungarian"], variants=["T1"], m_grid=(0.1,), preset="robot", workers=1, auto_m=False
    )
    assert {r.map for r in given.rows} == {"small"}


@pytest.mark.parametrize(
    "options, field",
    [
        ({"matchers": ["simplex"]}, "matchers"),
        ({"variants": ["T9"]}, "variants"),
        ({"variants": []}, "variants"),
        ({"m_grid": (0.1, -0.1)}, "m_grid"),
        ({"m_grid": ()}, "m_grid"),
        ({"m_grid": (0.1, 0.1)}, "m_grid"),
        ({"maps": ["nope"]}, "maps"),
        ({"config_overrides": {"m": 0.2}}, "config_overrides"),
        ({"config_overrides": {"no_such_option": 1}}, "config_overrides"),
        ({"legacy_scoring": "sometimes"}, "legacy"),
    ],
)
def test_bad_options_are_parameter_errors(synthetic_dataset, options, field):
    with pytest.raises(ParameterError) as raised:
        run_evaluation(synthetic_dataset, workers=1, **options)
    assert raised.value.field == field


def test_unknown_preset_is_reported_before_any_work(synthetic_dataset):
    calls = []
    with pytest.raises(ParameterError, match="no_such_preset"):
        run_evaluation(synthetic_dataset, workers=1, preset="no_such_preset", progress=lambda *a: calls.append(a))
    assert calls == []


def test_config_overrides_reach_the_matcher(synthetic_dataset):
    options = dict(
        matchers=["planar"], variants=["T4"], m_grid=(0.1,), preset="robot", workers=1, auto_m=False, human=False
    )
    plain = run_evaluation(synthetic_dataset, **options)
    assert any(row.seeds > 1 for row in plain.rows)
    capped = run_evaluation(synthetic_dataset, config_overrides={"max_seeds": 1}, **options)
    assert all(row.seeds <= 1 for row in capped.rows)
    assert capped.settings["config"]["max_seeds"] == 1


# --------------------------------------------------------------------------- real data


@pytest.mark.dataset
def test_three_kth_sketches_end_to_end():
    from ursim_core.evaluation.datasets import MISSING_REASON, dataset_root

    root = dataset_root()
    if root is None:
        pytest.skip(MISSING_REASON)
    result = run_evaluation(
        root / "ursim_kth_sketches",
        matchers=["planar", "hungarian"],
        variants=["T4", "baseline"],
        maps=["01", "03", "11"],
        workers=1,
    )
    assert {r.map for r in result.rows} == {"01", "03", "11"}
    assert len(result.rows) == 3 * 2 * 2 * 2 * (len(DEFAULT_M_GRID) + 1)
    for annotator in ("malcolm", "vasiliki"):
        oracle = result.summary(annotator, "planar", "T4", "oracle")
        fixed = result.summary(annotator, "planar", "T4", "fixed")
        auto = result.summary(annotator, "planar", "T4", "auto")
        assert oracle.n == fixed.n == auto.n == 3
        # The oracle is the best m of the grid per map, and the automatic m picks from that grid.
        assert all(o >= f - 1e-12 for o, f in zip(oracle.f1, fixed.f1))
        assert all(o >= a - 1e-12 for o, a in zip(oracle.f1, auto.f1))
        assert set(auto.m_values) <= set(DEFAULT_M_GRID)
        # URSIM finds some correct correspondences on these sketches.
        assert oracle.mean > 0.2
    human = {(s.annotator, s.variant): s for s in result.human_summaries}
    assert set(human) == {("malcolm", "vasiliki"), ("vasiliki", "malcolm")}
    # Two annotators of the same maps agree far more than any matcher does.
    assert all(s.mean > 0.5 for s in human.values())


def test_disk_cache_misses_when_a_map_changes(synthetic_dataset, tmp_path):
    import shutil

    dataset = tmp_path / "dataset"
    shutil.copytree(synthetic_dataset, dataset)
    options = dict(
        matchers=["hungarian"],
        variants=["T1"],
        m_grid=(0.1,),
        preset="robot",
        metric_preset="robot",
        workers=1,
        cache_dir=tmp_path / "segcache",
        auto_m=False,
        human=False,
    )
    run_evaluation(dataset, **options)
    Image.fromarray(plan_image(1.2)).save(dataset / "sketches" / "small.png")
    again = run_evaluation(dataset, **options)
    assert again.timings["maps"] == 4 and again.timings["maps_from_cache"] == 3


def test_an_exception_in_progress_stops_the_worker_pool(synthetic_dataset):
    class Cancelled(Exception):
        pass

    def cancel_when_matching(done, total, text):
        if text.startswith("match"):
            raise Cancelled(text)

    with pytest.raises(Cancelled):
        run_evaluation(
            synthetic_dataset,
            matchers=["planar", "hungarian"],
            variants=["T4", "T1"],
            m_grid=GRID,
            preset="robot",
            workers=2,
            progress=cancel_when_matching,
        )


def test_place_accuracy_is_one_where_every_clique_is_matched_right(synthetic_result):
    for row in synthetic_result.rows:
        assert math.isnan(row.place_accuracy) or 0.0 <= row.place_accuracy <= 1.0
        assert row.augment == ""
        if row.map == "copy" and row.f1 == 1.0:
            assert row.place_accuracy == 1.0
    # vasiliki annotated two of malcolm's three rooms: her cliques send the robot right for two
    # of malcolm's three cliques; malcolm's cliques are right for both of hers.
    human = synthetic_result.human_rows
    assert human
    for row in human:
        assert row.place_accuracy == pytest.approx(2 / 3 if row.annotator == "malcolm" else 1.0)
    summary = synthetic_result.summary("malcolm", "planar", "T4", "oracle")
    assert len(summary.place) == summary.n


def test_dihedral_augmentation_scores_each_orientation_with_its_ground_truth_turned(synthetic_dataset):
    result = run_evaluation(
        synthetic_dataset,
        matchers=["planar"],
        variants=["T4"],
        m_grid=GRID,
        preset="robot",
        metric_preset="robot",
        workers=1,
        augment="dihedral",
    )
    names = ["rot0", "rot90", "rot180", "rot270", "mirror-rot0", "mirror-rot90", "mirror-rot180", "mirror-rot270"]
    assert result.settings["augment"] == names
    assert {row.augment for row in result.rows} == set(names)
    assert len(result.rows) == 2 * 8 * 2 * (len(GRID) + 1)
    for row in result.rows:
        # The turned sketch keeps its three rooms; the metric map is not turned.
        assert row.n_sketch_regions == 3 and row.n_metric_regions == 3
    # The annotators' points move with the image: in every orientation they still fall in the
    # rooms they were clicked in, so humans agree exactly as upright.
    human = {(r.map, r.augment, r.annotator): r for r in result.human_rows}
    assert len(human) == 2 * 8 * 2
    for row in human.values():
        assert row.f1 == pytest.approx(0.8)
        assert row.place_accuracy == pytest.approx(2 / 3 if row.annotator == "malcolm" else 1.0)
    # Each (map, orientation) is a sample of its own in the summaries.
    summary = result.summary("malcolm", "planar", "T4", "auto")
    assert summary.n == 16 and "copy@mirror-rot90" in summary.maps
    assert not any("ground-truth point" in note for note in result.notes)


def test_a_missing_annotator_file_is_reported(synthetic_dataset, tmp_path):
    import shutil

    copy = tmp_path / "dataset"
    shutil.copytree(synthetic_dataset, copy)
    (copy / "gt_correspondences" / "vasiliki" / "gt_small_model_simple.dat").unlink()
    result = run_evaluation(
        copy, matchers=["planar"], variants=["T4"], m_grid=GRID, preset="robot", metric_preset="robot", workers=1
    )
    assert len(result.warnings) == 1
    assert "small" in result.warnings[0] and "vasiliki" in result.warnings[0]
    assert "malcolm only" in result.warnings[0] and result.warnings[0] in result.notes


# ---------------------------------------------------------------------- the one-to-one ceiling


def test_an_evaluation_reports_the_ceiling_beside_the_matcher(synthetic_dataset):
    result = run_evaluation(synthetic_dataset, matchers=["hungarian"], variants=["T4"], m_grid=(0.1,), workers=1)
    # malcolm annotated three rooms, vasiliki two of them: pairing all three is best for the mean
    # (1.0 and 0.8), as pairing two (0.8 and 1.0) is; the search keeps the first found.
    rows = {(r.map, r.annotator): r for r in result.ceiling_rows}
    assert set(rows) == {(m, a) for m in ("copy", "small") for a in ("malcolm", "vasiliki")}
    for (_, annotator), row in rows.items():
        assert row.matcher == "ceiling" and row.variant == "one-to-one" and row.n_pairs == 3
        assert row.f1 == pytest.approx(1.0 if annotator == "malcolm" else 0.8)
        assert row.place_accuracy == pytest.approx(1.0)
    assert result.ceiling_summary.mean == pytest.approx(0.9)
    assert "Ceiling (the best one-to-one answer" in tables.format_tables(result)
    assert "## Ceiling of a one-to-one matcher" in report.markdown_summary(result)
    header, sketch_rows = tables.per_sketch_table(result, "hungarian", "T4")
    assert header[-1] == "ceiling" and all(row[-1] == "0.90 / 1.00" for row in sketch_rows)
    csv_rows = [line for line in report.runs_csv(result).splitlines() if ",ceiling," in line]
    assert len(csv_rows) == 4


def test_legacy_scoring_has_no_ceiling(synthetic_dataset):
    result = run_evaluation(
        synthetic_dataset, matchers=["hungarian"], variants=["T4"], m_grid=(0.1,), workers=1, legacy_scoring="fnfix"
    )
    assert result.ceiling_rows == () and result.ceiling_summary is None
    assert "Ceiling" not in tables.format_tables(result)
