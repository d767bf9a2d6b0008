"""Touching pieces and the features of a pair, kept up to date while pieces merge.

:class:`PieceGraph` holds, per piece, sums that merging adds up (area, perimeter, image
moments, largest clearance) and, per touching pair, sums over the 4-adjacent pixel pairs of
their shared boundary (length, largest and summed clearance, how often MAORIS or the
watershed put a boundary there). The features of a pair (:data:`FEATURE_NAMES`) are ratios
of these, free of the map's scale; ``a`` is the smaller piece of the pair, ``b`` the larger.

Examples
--------
>>> import numpy as np
>>> labels = np.zeros((20, 40), np.int32)
>>> labels[2:18, 2:19] = 1; labels[2:18, 19:38] = 2          # two pieces, one straight seam
>>> graph = PieceGraph.from_arrays(labels, labels, labels, np.ones(labels.shape, np.float32))
>>> graph.pairs()
[(1, 2)]
>>> features = graph.features([(1, 2)])
>>> round(float(features[0, FEATURE_NAMES.index("boundary_per_side")]), 2)  # 16 px of seam / sqrt(272 px)
0.97
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["FEATURE_NAMES", "PieceGraph"]

#: The pair features, in the column order of :meth:`PieceGraph.features`.
FEATURE_NAMES: tuple[str, ...] = (
    "log_area_small",  # log of the smaller piece's share of the free space
    "log_area_large",
    "size_ratio",  # smaller / larger area
    "boundary_of_small",  # shared boundary / perimeter of the smaller piece
    "boundary_of_large",
    "boundary_per_side",  # shared boundary / sqrt(area of the smaller piece)
    "saddle_ratio",  # widest clearance on the boundary / smaller of the two peak clearances
    "saddle_of_large_peak",  # ... / larger peak clearance
    "mean_to_saddle",  # mean clearance on the boundary / widest
    "saddle_per_map",  # widest clearance / sqrt(free area)
    "compact_small",  # 4 pi area / perimeter^2
    "compact_large",
    "compact_union",
    "elongation_small",  # 1 - sqrt(minor / major second moment)
    "elongation_large",
    "elongation_union",
    "maoris_cut",  # share of the boundary where MAORIS separates the two sides
    "watershed_cut",
)

# Columns of the per-pair boundary sums.
_LENGTH, _SADDLE, _CLEARANCE, _MAORIS, _WATERSHED = range(5)


def _neighbour_pairs(labels: np.ndarray):
    """Indices (flat) of 4-adjacent pixel pairs with different non-zero labels."""
    rows, cols = labels.shape
    index = np.arange(labels.size).reshape(rows, cols)
    firsts, seconds = [], []
    for a, b, ia, ib in (
        (labels[:, :-1], labels[:, 1:], index[:, :-1], index[:, 1:]),
        (labels[:-1, :], labels[1:, :], index[:-1, :], index[1:, :]),
    ):
        touching = (a != b) & (a != 0) & (b != 0)
        firsts.append(ia[touching])
        seconds.append(ib[touching])
    return np.concatenate(firsts), np.concatenate(seconds)


def _perimeters(labels: np.ndarray, count: int) -> np.ndarray:
    """Per label, the number of its pixel sides facing another label, an obstacle or the border."""
    padded = np.pad(labels, 1)
    out = np.zeros(count, np.float64)
    for a, b in ((padded[:, :-1], padded[:, 1:]), (padded[:-1, :], padded[1:, :])):
        differ = a != b
        out += np.bincount(a[differ], minlength=count)[:count]
        out += np.bincount(b[differ], minlength=count)[:count]
    out[0] = 0.0
    return out


class PieceGraph:
    """Pieces, their touching pairs and the sums the pair features are made of.

    Build with :meth:`from_arrays` (or :meth:`from_pieces`); :meth:`merge` joins two
    touching pieces into the first one and updates every sum.
    """

    def __init__(self, pieces: dict, boundaries: dict, free_area: float):
        #: piece id -> float64 array [area, perimeter, peak, sum r, sum c, sum rr, sum cc, sum rc]
        self.pieces = pieces
        #: (a, b) with a < b -> float64 array [length, saddle, clearance sum, MAORIS cuts, watershed cuts]
        self.boundaries = boundaries
        self.free_area = float(free_area)
        self.neighbours: dict[int, set[int]] = {p: set() for p in pieces}
        for a, b in boundaries:
            self.neighbours[a].add(b)
            self.neighbours[b].add(a)

    @classmethod
    def from_pieces(cls, pieces) -> PieceGraph:
        """From :class:`~ursim_core.segmentation.learned.pieces.CandidatePieces`."""
        return cls.from_arrays(pieces.labels, pieces.maoris, pieces.watershed, pieces.clearance)

    @classmethod
    def from_arrays(
        cls, labels: np.ndarray, maoris: np.ndarray, watershed: np.ndarray, clearance: np.ndarray
    ) -> PieceGraph:
        """From a piece label image (0 = obstacle), the two segmentations and the clearance."""
        labels = np.asarray(labels, np.int64)
        count = int(labels.max()) + 1
        flat = labels.ravel()
        rows, cols = np.indices(labels.shape, dtype=np.float64)
        r, c = rows.ravel(), cols.ravel()
        area = np.bincount(flat, minlength=count).astype(np.float64)
        moments = [np.bincount(flat, weights=w, minlength=count) for w in (r, c, r * r, c * c, r * c)]
        peak = np.zeros(count, np.float64)
        np.maximum.at(peak, flat, np.asarray(clearance, np.float64).ravel())
        perimeter = _perimeters(labels, count)
        pieces = {
            p: np.array([area[p], perimeter[p], peak[p], *(m[p] for m in moments)])
            for p in range(1, count)
            if area[p] > 0
        }
        first, second = _neighbour_pairs(labels)
        boundaries: dict[tuple[int, int], np.ndarray] = {}
        if first.size:
            la, lb = flat[first], flat[second]
            low, high = np.minimum(la, lb), np.maximum(la, lb)
            keys, inverse = np.unique(low * count + high, return_inverse=True)
            clear = np.minimum(clearance.ravel()[first], clearance.ravel()[second]).astype(np.float64)
            m_flat, w_flat = np.asarray(maoris).ravel(), np.asarray(watershed).ravel()
            length = np.bincount(inverse, minlength=len(keys)).astype(np.float64)
            saddle = np.zeros(len(keys))
            np.maximum.at(saddle, inverse, clear)
            sums = np.bincount(inverse, weights=clear, minlength=len(keys))
            m_cut = np.bincount(inverse, weights=(m_flat[first] != m_flat[second]), minlength=len(keys))
            w_cut = np.bincount(inverse, weights=(w_flat[first] != w_flat[second]), minlength=len(keys))
            for k, key in enumerate(keys.tolist()):
                boundaries[(key // count, key % count)] = np.array([length[k], saddle[k], sums[k], m_cut[k], w_cut[k]])
        return cls(pieces, boundaries, free_area=float(area[1:].sum()))

    def pairs(self) -> list[tuple[int, int]]:
        """Touching pairs (a, b), a < b, sorted."""
        return sorted(self.boundaries)

    def boundary(self, a: int, b: int) -> np.ndarray:
        return self.boundaries[(a, b) if a < b else (b, a)]

    def merge(self, keep: int, gone: int) -> None:
        """Join piece ``gone`` into touching piece ``keep``."""
        shared = self.boundaries.pop((keep, gone) if keep < gone else (gone, keep))
        p, q = self.pieces[keep], self.pieces.pop(gone)
        merged = p + q
        merged[1] = p[1] + q[1] - 2.0 * shared[_LENGTH]
        merged[2] = max(p[2], q[2])
        self.pieces[keep] = merged
        self.neighbours[keep].discard(gone)
        for other in self.neighbours.pop(gone):
            if other == keep:
                continue
            moved = self.boundaries.pop((gone, other) if gone < other else (other, gone))
            self.neighbours[other].discard(gone)
            key = (keep, other) if keep < other else (other, keep)
            if key in self.boundaries:
                existing = self.boundaries[key]
                existing[_SADDLE] = max(existing[_SADDLE], moved[_SADDLE])
                for column in (_LENGTH, _CLEARANCE, _MAORIS, _WATERSHED):
                    existing[column] += moved[column]
            else:
                self.boundaries[key] = moved
                self.neighbours[keep].add(other)
                self.neighbours[other].add(keep)

    def features(self, pairs: list[tuple[int, int]]) -> np.ndarray:
        """The features (:data:`FEATURE_NAMES`) of touching pairs, shape (pairs, features)."""
        out = np.zeros((len(pairs), len(FEATURE_NAMES)), np.float64)
        scale = math.sqrt(max(self.free_area, 1.0))
        for i, (x, y) in enumerate(pairs):
            a, b = self.pieces[x], self.pieces[y]
            if a[0] > b[0]:
                a, b = b, a
            edge = self.boundary(x, y)
            union = a + b
            union[1] = a[1] + b[1] - 2.0 * edge[_LENGTH]
            length, saddle = edge[_LENGTH], edge[_SADDLE]
            small_peak, large_peak = min(a[2], b[2]), max(a[2], b[2])
            out[i] = (
                math.log(a[0] / self.free_area),
                math.log(b[0] / self.free_area),
                a[0] / b[0],
                length / a[1],
                length / b[1],
                length / math.sqrt(a[0]),
                saddle / small_peak if small_peak > 0 else 0.0,
                saddle / large_peak if large_peak > 0 else 0.0,
                edge[_CLEARANCE] / length / saddle if saddle > 0 else 0.0,
                saddle / scale,
                _compactness(a),
                _compactness(b),
                _compactness(union),
                _elongation(a),
                _elongation(b),
                _elongation(union),
                edge[_MAORIS] / length,
                edge[_WATERSHED] / length,
            )
        return np.round(out, 6)


def _compactness(piece: np.ndarray) -> float:
    return 4.0 * math.pi * piece[0] / (piece[1] * piece[1]) if piece[1] > 0 else 0.0


def _elongation(piece: np.ndarray) -> float:
    area = piece[0]
    mr, mc = piece[3] / area, piece[4] / area
    vrr, vcc, vrc = piece[5] / area - mr * mr, piece[6] / area - mc * mc, piece[7] / area - mr * mc
    half_trace, det = (vrr + vcc) / 2.0, vrr * vcc - vrc * vrc
    spread = math.sqrt(max(half_trace * half_trace - det, 0.0))
    major, minor = half_trace + spread, max(half_trace - spread, 0.0)
    return 1.0 - math.sqrt(minor / major) if major > 0 else 0.0
