"""Benchmarks of the URSIM matcher: KTH sketches (time per match, full m sweep) and scale.

Run ``python -m ursim_core.bench.matching [--datasets PATH] [--sizes 300 1000] [--accuracy]``.
Figures are printed, never asserted (speed targets belong here, not in unit tests).

- :func:`bench_kth`: segments the 18 KTH sketches and the model once (cached in memory), then times
  :func:`ursim_core.matching.match_prepared` at one m per pair (median over pairs), ``prepare`` per
  pair, and the whole evaluation of URSIM planar over the 20-value m sweep for both annotators
  (segmentation excluded).
- :func:`bench_scale`: generated region graphs (:func:`random_region_graph`: Delaunay
  triangulation of random points, pruned to a random spanning tree plus a fraction of the other
  edges) matched against a perturbed, relabelled copy (:func:`perturbed_copy`); prints time,
  tracemalloc peak and the memory still held afterwards (growth), and the F1 of the recovered
  correspondence against the known identity.
"""

from __future__ import annotations

import argparse
import statistics
import time
import tracemalloc

import networkx as nx
import numpy as np
from scipy.spatial import Delaunay

__all__ = ["random_region_graph", "perturbed_copy", "bench_kth", "bench_kth_turned", "bench_scale", "main"]


def random_region_graph(n: int, *, seed: int = 0, keep_fraction: float = 0.5) -> nx.Graph:
    """A connected planar region graph with region-like attributes.

    Points uniform in a square; edges = a random spanning tree of their Delaunay
    triangulation plus ``keep_fraction`` of the remaining Delaunay edges (so the graph
    stays planar and connected). Nodes get ``size`` (log-normal pixels), ``pca_shape``
    (uniform in [0, 1)) and ``centroid`` (the point, as (row, col)).

    Examples
    --------
    >>> g = random_region_graph(50, seed=1)
    >>> g.number_of_nodes(), nx.is_connected(g)
    (50, True)
    """
    rng = np.random.default_rng(seed)
    side = 100.0 * np.sqrt(n)
    points = rng.uniform(0.0, side, size=(n, 2))
    graph = nx.Graph()
    for node, (row, col) in enumerate(points):
        graph.add_node(
            node,
            size=int(rng.lognormal(8.0, 0.8)),
            pca_shape=float(rng.uniform(0.0, 1.0)),
            centroid=(float(row), float(col)),
        )
    if n < 2:
        return graph
    delaunay_edges = set()
    if n == 2:
        delaunay_edges.add((0, 1))
    else:
        for simplex in Delaunay(points).simplices:
            for a, b in ((0, 1), (1, 2), (0, 2)):
                u, v = int(simplex[a]), int(simplex[b])
                delaunay_edges.add((min(u, v), max(u, v)))
    full = nx.Graph()
    full.add_nodes_from(range(n))
    for u, v in delaunay_edges:
        full.add_edge(u, v, weight=float(rng.uniform()))
    tree = nx.minimum_spanning_tree(full, weight="weight")
    tree_edges = {(min(u, v), max(u, v)) for u, v in tree.edges()}
    for u, v in sorted(delaunay_edges):
        if (u, v) in tree_edges or rng.uniform() < keep_fraction:
            graph.add_edge(u, v, boundary=1)
    return graph


def perturbed_copy(
    graph: nx.Graph,
    *,
    seed: int = 0,
    size_noise: float = 0.05,
    position_noise: float = 5.0,
    label_offset: int = 10_000,
) -> tuple[nx.Graph, dict]:
    """A relabelled copy with noisy sizes and centroids.

    Returns
    -------
    copy : networkx.Graph
    mapping : dict
        Original node -> node of the copy (the true correspondence).

    Examples
    --------
    >>> g = random_region_graph(10, seed=2)
    >>> copy, mapping = perturbed_copy(g, seed=3)
    >>> nx.is_isomorphic(g, copy), len(mapping)
    (True, 10)
    """
    rng = np.random.default_rng(seed)
    nodes = sorted(graph.nodes)
    new_ids = rng.permutation(len(nodes)) + label_offset
    mapping = {node: int(new_id) for node, new_id in zip(nodes, new_ids)}
    copy = nx.Graph()
    for node in nodes:
        attributes = graph.nodes[node]
        row, col = attributes["centroid"]
        copy.add_node(
            mapping[node],
            size=max(1, int(round(attributes["size"] * rng.lognormal(0.0, size_noise)))),
            pca_shape=float(np.clip(attributes["pca_shape"] + rng.normal(0.0, size_noise / 4), 0.0, 1.0)),
            centroid=(row + rng.normal(0.0, position_noise), col + rng.normal(0.0, position_noise)),
        )
    copy.add_edges_from((mapping[u], mapping[v], data) for u, v, data in graph.edges(data=True))
    return copy, mapping


def _identity_f1(pairs, mapping) -> float:
    if not pairs:
        return 0.0
    correct = sum(1 for a, b in pairs if mapping.get(a) == b)
    precision = correct / len(pairs)
    recall = correct / len(mapping)
    return 0.0 if correct == 0 else 2 * precision * recall / (precision + recall)


def bench_scale(sizes=(300, 1000), *, m: float = 0.01, seed: int = 0, config=None) -> list[dict]:
    """Time and memory of matching generated graphs against perturbed copies.

    Parameters
    ----------
    sizes : sequence of int
        Region counts.
    m : float
        Threshold used when ``config`` is not given.
    config : MatchConfig, optional
        Default: the default configuration with the fixed ``m``. Pass ``MatchConfig()``
        to time the automatic m (a sweep over the 20 values of the grid).

    Returns
    -------
    list of dict
        Per size: ``n``, ``edges``, ``prepare_s``, ``match_s``, ``peak_mib``,
        ``growth_mib``, ``seeds``, ``pairs``, ``f1``.
    """
    from ursim_core.matching import MatchConfig, match_prepared, prepare

    config = MatchConfig(m=m) if config is None else config
    rows = []
    for n in sizes:
        graph = random_region_graph(n, seed=seed)
        copy, mapping = perturbed_copy(graph, seed=seed + 1)
        # Timing and memory are measured in separate runs: tracemalloc slows Python code several-fold.
        start = time.perf_counter()
        prepared = prepare(graph, copy, config)
        prepared_at = time.perf_counter()
        result = match_prepared(prepared)
        done = time.perf_counter()
        del prepared
        tracemalloc.start()
        before = tracemalloc.get_traced_memory()[0]
        prepared = prepare(graph, copy, config)
        match_prepared(prepared)
        peak = tracemalloc.get_traced_memory()[1]
        del prepared
        after = tracemalloc.get_traced_memory()[0]
        tracemalloc.stop()
        rows.append(
            dict(
                n=n,
                edges=graph.number_of_edges(),
                prepare_s=prepared_at - start,
                match_s=done - prepared_at,
                peak_mib=(peak - before) / 2**20,
                growth_mib=(after - before) / 2**20,
                seeds=result.seeds_count,
                pairs=len(result.pairs),
                f1=_identity_f1(result.pairs, mapping),
            )
        )
        print(
            f"scale n={n:5d} edges={rows[-1]['edges']:5d}: prepare {rows[-1]['prepare_s']:.3f} s, "
            f"match {rows[-1]['match_s']:.3f} s, tracemalloc peak {rows[-1]['peak_mib']:.1f} MiB, "
            f"growth {rows[-1]['growth_mib']:.2f} MiB, seeds {result.seeds_count}, "
            f"pairs {len(result.pairs)}, F1 vs truth {rows[-1]['f1']:.3f}",
            flush=True,
        )
    return rows


def bench_kth(dataset_root=None, *, m: float = 0.1, repeats: int = 3) -> dict:
    """Time the matcher on the KTH sketches (segmentations computed once, not timed).

    For the default configuration (recommended pipeline) and the released one (released
    pipeline) it prints: the median and max time of one ``match_prepared`` at ``m`` per
    sketch/model pair (best of ``repeats``), the median ``prepare`` time, the time of
    the whole evaluation of the planar matcher over the 20-value m sweep for the 18
    sketches with both annotators' scoring (prepare included, segmentation excluded), and
    for the default configuration the median time of one ``m='auto'`` match.

    Returns
    -------
    dict
        The printed figures, keyed ``<config>_<figure>`` (milliseconds or seconds as named).
    """
    from ursim_core.evaluation.datasets import dataset_root as locate
    from ursim_core.evaluation.kth_protocol import kth_pairs, score_pairs
    from ursim_core.matching import M_GRID, MatchConfig, match_prepared, prepare

    root = locate(dataset_root)
    if root is None:
        print("bench_kth: datasets not found, skipped")
        return {}
    figures = {}
    for label, pipeline, config in (
        ("default", "recommended", MatchConfig()),
        ("released", "released", MatchConfig.released()),
    ):
        cases = kth_pairs(root, pipeline=pipeline)
        print(
            f"kth {label}: {len(cases.sketches)} sketches + model, {pipeline} pipeline: segmentation "
            f"{cases.segmentation_seconds:.1f} s (0 when already done in this process; not counted below)",
            flush=True,
        )
        prepare_times, match_times, auto_times = [], [], []
        for sketch in cases.sketches.values():
            t0 = time.perf_counter()
            prepared = prepare(sketch, cases.model, config)
            prepare_times.append(time.perf_counter() - t0)
            runs = []
            for _ in range(repeats):
                t0 = time.perf_counter()
                match_prepared(prepared, m)
                runs.append(time.perf_counter() - t0)
            match_times.append(min(runs))
            if label == "default":
                t0 = time.perf_counter()
                match_prepared(prepared)
                auto_times.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        for name, sketch in cases.sketches.items():
            prepared = prepare(sketch, cases.model, config)
            for grid_m in M_GRID:
                result = match_prepared(prepared, grid_m)
                for annotator in cases.references:
                    score_pairs(result.pairs, cases.reference(annotator, name))
        sweep = time.perf_counter() - t0
        figures[f"{label}_match_median_ms"] = 1000 * statistics.median(match_times)
        figures[f"{label}_match_max_ms"] = 1000 * max(match_times)
        figures[f"{label}_prepare_median_ms"] = 1000 * statistics.median(prepare_times)
        figures[f"{label}_sweep_s"] = sweep
        line = (
            f"kth {label}: one match at m={m}: median {figures[f'{label}_match_median_ms']:.2f} ms, "
            f"max {figures[f'{label}_match_max_ms']:.2f} ms; prepare median "
            f"{figures[f'{label}_prepare_median_ms']:.2f} ms; 20-m sweep + scoring, "
            f"{len(cases.sketches)} sketches x {len(cases.references)} annotators: {sweep:.2f} s"
        )
        if auto_times:
            figures[f"{label}_auto_median_ms"] = 1000 * statistics.median(auto_times)
            line += f"; one m='auto' match: median {figures[f'{label}_auto_median_ms']:.1f} ms"
        print(line, flush=True)
    return figures


def bench_kth_turned(dataset_root=None, *, degrees: float = 30.0, repeats: int = 3) -> dict:
    """Time the default matcher on the KTH sketches turned by ``degrees``: resampled onto their wall
    axes and segmented in several resamplings, whose answers the planar matcher votes over
    (:mod:`ursim_core.matching.resampling`); with the others in the first one's orientations
    (``vote_orientations='first'``); and with one segmentation (``resampling_vote=False``).

    Prints and returns the median over the sketches of each sketch's median prepare-and-match time
    (automatic m) over ``repeats`` runs, milliseconds, per variant; the segmentations are made
    first and not timed. The runs of the variants are interleaved, sketch by sketch, so that a busy
    moment of a shared machine falls on all of them alike.
    """
    from ursim_core.evaluation.augment import Orientation, transform_image
    from ursim_core.evaluation.datasets import dataset_root as locate
    from ursim_core.io.maps import load_map
    from ursim_core.matching import MatchConfig, match_prepared, prepare
    from ursim_core.segmentation import segment, segment_canonical

    root = locate(dataset_root)
    if root is None:
        print("bench_kth_turned: datasets not found, skipped")
        return {}
    folder = root / "ursim_kth_sketches"
    model = segment(load_map(folder / "model" / "model_simple.png"), preset="default")
    sketches = [
        segment_canonical(transform_image(load_map(path).free, Orientation(degrees)), preset="default", resampled=True)
        for path in sorted((folder / "sketches").glob("*.png"))
    ]
    figures = {}
    variants = (
        ("voted", MatchConfig()),
        ("first", MatchConfig(vote_orientations="first")),
        ("single", MatchConfig(resampling_vote=False)),
    )
    runs: dict[str, list[list[float]]] = {label: [] for label, _ in variants}
    for sketch in sketches:
        for label, _ in variants:
            runs[label].append([])
        for _ in range(max(1, repeats)):
            for label, config in variants:
                # A fresh copy each run, and no wall angle remembered by content: what an earlier
                # run cached would make the later ones look faster than a first match.
                fresh = _uncached(sketch)
                forget_remembered()
                t0 = time.perf_counter()
                match_prepared(prepare(fresh, model, config))
                runs[label][-1].append(time.perf_counter() - t0)
    for label, _ in variants:
        per_sketch = [statistics.median(times) for times in runs[label]]
        figures[f"turned_{label}_median_ms"] = 1000 * statistics.median(per_sketch)
    print(
        f"kth turned by {degrees:g} degrees: prepare + automatic m median {figures['turned_voted_median_ms']:.1f} ms "
        f"with the vote over {min(1 + len(sketches[0].resampled), MatchConfig().vote_segmentations)} segmentations, "
        f"{figures['turned_first_median_ms']:.1f} ms with vote_orientations='first', "
        f"{figures['turned_single_median_ms']:.1f} ms with one segmentation (median over the sketches of each one's "
        f"median of {max(1, repeats)} runs; segmentations not counted)",
        flush=True,
    )
    return figures


def forget_remembered() -> None:
    """Empty the memos by content that a match fills (the wall angles of label images, the
    Python loop's alignments), so that the next match is timed as a first one."""
    from ursim_core.matching import alignment_memo
    from ursim_core.segmentation import canonical

    canonical._voted_angle.cache_clear()
    alignment_memo.forget()


def _uncached(segmentation):
    """The same segmentation (and resamplings) without the graph and wall angle it has cached."""
    from ursim_core.segmentation import Segmentation

    return Segmentation(
        segmentation.labels,
        None if segmentation._regions is not None else segmentation.graph,
        segmentation.method,
        segmentation.params,
        segmentation.source,
        regions=segmentation._regions,
        resampled=tuple(map(_uncached, segmentation.resampled)),
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--datasets", default=None)
    parser.add_argument("--sizes", type=int, nargs="*", default=[300, 1000])
    parser.add_argument("--auto-sizes", type=int, nargs="*", default=[300, 1000], help="sizes also timed with m='auto'")
    parser.add_argument("--skip-kth", action="store_true")
    parser.add_argument("--accuracy", action="store_true", help="also print the KTH accuracy table")
    arguments = parser.parse_args(argv)
    if arguments.accuracy:
        from ursim_core.evaluation.kth_protocol import accuracy_report

        accuracy_report(arguments.datasets)
    if not arguments.skip_kth:
        bench_kth(arguments.datasets)
        bench_kth_turned(arguments.datasets)
    if arguments.sizes:
        bench_scale(tuple(arguments.sizes))
    if arguments.auto_sizes:
        from ursim_core.matching import MatchConfig

        print("with m='auto':")
        bench_scale(tuple(arguments.auto_sizes), config=MatchConfig())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
