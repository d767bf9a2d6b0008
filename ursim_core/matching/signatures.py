"""Heat-kernel signatures on a vertex-weighted Laplacian, and their distances.

Steps 6-8 of :mod:`ursim_core.matching.descriptors`: the Chung-Langlands vertex-weighted
Laplacian, anchor signatures ``s_u(t) = sum_a H_t(u, a)`` (or the plain HKS) with
``H_t = exp(-t L)``, and ``c(v, v') = mean_t |s_v(t) - s_v'(t)|``.
"""

from __future__ import annotations

from collections.abc import Sequence

import networkx as nx
import numpy as np

from ursim_core.matching.config import DEFAULT_TIMES

__all__ = ["DEFAULT_TIMES", "DENSE_LIMIT", "weighted_laplacian", "heat_kernel_signatures", "signature_distance"]

#: Largest graph handled by dense eigendecomposition; larger graphs use expm_multiply.
DENSE_LIMIT = 100


def weighted_laplacian(
    graph: nx.Graph, weights: np.ndarray, *, nodes: Sequence | None = None, dense: bool | None = None
):
    """Vertex-weighted Laplacian (Chung and Langlands).

    ``L(u,u) = sum_{v~u} w_v``, ``L(u,v) = -sqrt(w_u w_v)`` when u ~ v, else 0.
    It is symmetric positive semi-definite and ``L @ sqrt(w) = 0``.

    Parameters
    ----------
    graph : networkx.Graph
    weights : ndarray, shape (n,)
        Non-negative vertex weights in ``nodes`` order.
    nodes : sequence, optional
        Row order; default ascending node ids.
    dense : bool, optional
        Return a dense ndarray (default when ``n <= DENSE_LIMIT``) or a CSR matrix.

    Examples
    --------
    >>> g = nx.path_graph(3)
    >>> weighted_laplacian(g, np.array([1.0, 4.0, 1.0])).tolist()
    [[4.0, -2.0, 0.0], [-2.0, 2.0, -2.0], [0.0, -2.0, 4.0]]
    """
    nodes = sorted(graph.nodes) if nodes is None else list(nodes)
    weights = np.asarray(weights, dtype=np.float64)
    if np.any(weights < 0):
        raise ValueError("vertex weights must be non-negative")
    n = len(nodes)
    if dense is None:
        dense = n <= DENSE_LIMIT
    index = {node: i for i, node in enumerate(nodes)}
    edges = np.array([(index[a], index[b]) for a, b in graph.edges() if a != b], dtype=np.int64).reshape(-1, 2)
    rows = np.concatenate([edges[:, 0], edges[:, 1]])
    cols = np.concatenate([edges[:, 1], edges[:, 0]])
    root = np.sqrt(weights)
    if dense:
        # The same sums in the same order as the CSR product below (row by row, columns
        # ascending), so both paths give bit-identical matrices.
        order = np.lexsort((cols, rows))
        rows, cols = rows[order], cols[order]
        degree_weights = np.zeros(n)
        np.add.at(degree_weights, rows, weights[cols])
        laplacian = np.zeros((n, n))
        laplacian[rows, cols] = -root[rows] * root[cols]
        laplacian[np.arange(n), np.arange(n)] += degree_weights
        return laplacian
    import scipy.sparse as sparse

    adjacency = sparse.csr_matrix((np.ones(rows.size), (rows, cols)), shape=(n, n))
    degree_weights = adjacency @ weights
    off_diagonal = sparse.csr_matrix((-root[rows] * root[cols], (rows, cols)), shape=(n, n))
    return (off_diagonal + sparse.diags(degree_weights)).tocsr()


def _uniform_grid(times: np.ndarray) -> bool:
    if times.size < 3:
        return True
    steps = np.diff(times)
    return bool(np.allclose(steps, steps[0], rtol=1e-9, atol=1e-12))


def _expm_apply(laplacian, vectors: np.ndarray, times: np.ndarray) -> np.ndarray:
    """``exp(-t L) @ vectors`` for every t: array of shape (len(times), n, k)."""
    import scipy.sparse as sparse
    from scipy.sparse.linalg import expm_multiply

    operator = sparse.csr_matrix(laplacian)
    if _uniform_grid(times) and times.size > 1:
        return np.asarray(
            expm_multiply(
                -operator, vectors, start=float(times[0]), stop=float(times[-1]), num=times.size, endpoint=True
            )
        )
    return np.stack([expm_multiply(-float(t) * operator, vectors) for t in times])


def heat_kernel_signatures(
    laplacian,
    *,
    anchors: Sequence[int] | None = None,
    times: Sequence[float] = DEFAULT_TIMES,
    method: str = "auto",
    block: int = 256,
) -> np.ndarray:
    """Heat-kernel signatures of every vertex.

    Parameters
    ----------
    laplacian : ndarray or sparse matrix, shape (n, n)
        From :func:`weighted_laplacian`.
    anchors : sequence of int, optional
        Row indices of the anchor vertices. Given: anchor signature
        ``s_u(t) = sum_a H_t(u, a)`` (an empty list gives zeros). None: plain heat
        kernel signature ``H_t(u, u)``.
    times : sequence of float
        Sample times.
    method : {'auto', 'eigh', 'expm'}
        ``'eigh'``: dense eigendecomposition (tiny negative eigenvalues from rounding
        are clipped to 0). ``'expm'``: ``scipy.sparse.linalg.expm_multiply`` on the
        anchor indicator vector (anchor signature) or on blocks of identity columns
        keeping only the diagonal (plain HKS). ``'auto'``: eigh up to
        ``DENSE_LIMIT`` vertices.
    block : int
        Identity columns per expm_multiply call for the plain HKS.

    Returns
    -------
    ndarray, shape (n, len(times))

    Examples
    --------
    >>> L = weighted_laplacian(nx.path_graph(3), np.ones(3))
    >>> s = heat_kernel_signatures(L, anchors=[0], times=[0.0, 1.0])
    >>> (s[:, 0].round(12) + 0.0).tolist()
    [1.0, 0.0, 0.0]
    >>> bool(np.allclose(s, heat_kernel_signatures(L, anchors=[0], times=[0.0, 1.0], method="expm")))
    True
    """
    times = np.asarray(times, dtype=np.float64)
    n = laplacian.shape[0]
    if n == 0:
        return np.zeros((0, times.size))
    if method == "auto":
        method = "eigh" if n <= DENSE_LIMIT else "expm"
    if method == "eigh":
        dense = laplacian.toarray() if hasattr(laplacian, "toarray") else np.asarray(laplacian, dtype=np.float64)
        eigenvalues, eigenvectors = np.linalg.eigh(dense)
        decay = np.exp(-np.outer(np.clip(eigenvalues, 0.0, None), times))  # (k, T)
        if anchors is None:
            return np.square(eigenvectors) @ decay
        indicator = np.zeros(n)
        indicator[list(anchors)] = 1.0
        projection = eigenvectors.T @ indicator  # (k,)
        return eigenvectors @ (projection[:, None] * decay)
    if method == "expm":
        if anchors is not None:
            indicator = np.zeros((n, 1))
            indicator[list(anchors), 0] = 1.0
            if not indicator.any():
                return np.zeros((n, times.size))
            return _expm_apply(laplacian, indicator, times)[:, :, 0].T
        diagonal = np.empty((n, times.size))
        for start in range(0, n, block):
            stop = min(n, start + block)
            columns = np.zeros((n, stop - start))
            columns[np.arange(start, stop), np.arange(stop - start)] = 1.0
            heat = _expm_apply(laplacian, columns, times)  # (T, n, b)
            diagonal[start:stop] = heat[:, np.arange(start, stop), np.arange(stop - start)].T
        return diagonal
    raise ValueError(f"method must be 'auto', 'eigh' or 'expm', not {method!r}")


def signature_distance(first: np.ndarray, second: np.ndarray, *, chunk_bytes: int = 32 << 20) -> np.ndarray:
    """``c(v, v') = mean_t |s_v(t) - s_v'(t)|`` for every pair of rows.

    Computed in row chunks so that large graphs do not build an (n, n', T) array at once.

    Examples
    --------
    >>> signature_distance(np.array([[1.0, 0.0]]), np.array([[1.0, 0.0], [0.0, 0.0]])).tolist()
    [[0.0, 0.5]]
    """
    first = np.asarray(first, dtype=np.float64)
    second = np.asarray(second, dtype=np.float64)
    n, n2 = first.shape[0], second.shape[0]
    result = np.empty((n, n2))
    if n == 0 or n2 == 0:
        return result
    samples = max(1, first.shape[1])
    rows_per_chunk = max(1, chunk_bytes // (8 * samples * max(1, n2)))
    for start in range(0, n, rows_per_chunk):
        stop = min(n, start + rows_per_chunk)
        result[start:stop] = np.abs(first[start:stop, None, :] - second[None, :, :]).mean(axis=2)
    return result
