"""Pictures for the command line: segmentation overlays and side-by-side match figures.

All functions return RGB uint8 arrays (rows, cols, 3); :func:`save_png` writes them atomically.
"""

from __future__ import annotations

import colorsys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import cv2
import numpy as np

from ursim_core.errors import UrsimError
from ursim_core.io.atomic import atomic_write_bytes
from ursim_core.segmentation.regions import row_bands

if TYPE_CHECKING:  # networkx is imported where a graph is made (_shrunk), not to draw one
    import networkx as nx

__all__ = [
    "FIGURE_MAX_SIDE",
    "distinct_colors",
    "label_colors",
    "overlay_segmentation",
    "side_by_side_matches",
    "save_png",
]

_GOLDEN = 0.618033988749895

#: Longest side, in pixels, at which :func:`side_by_side_matches` draws a map (larger ones are
#: scaled down): every KTH sketch and robot map is smaller, a 8000 x 8000 building is halved.
FIGURE_MAX_SIDE = 4000
#: Largest text scale of the region ids (reached at 1400 px; every KTH map is below): ids that
#: grow with the image cover many rooms of a building map and take seconds to draw.
_TEXT_SCALE_MAX = 2.0


def distinct_colors(n: int, *, saturation: float = 0.65, value: float = 0.95) -> np.ndarray:
    """``n`` well-separated RGB colours (golden-ratio hue steps), uint8, shape (n, 3).

    The k-th colour never changes when ``n`` grows, so region k keeps its colour.

    Examples
    --------
    >>> distinct_colors(3).shape
    (3, 3)
    >>> bool((distinct_colors(5)[:3] == distinct_colors(3)).all())
    True
    """
    hues = (np.arange(n) * _GOLDEN) % 1.0
    return np.array(
        [[round(255 * c) for c in colorsys.hsv_to_rgb(h, saturation, value)] for h in hues], dtype=np.uint8
    ).reshape(n, 3)


def label_colors(labels: np.ndarray, colors: dict[int, Sequence[int]] | None = None) -> np.ndarray:
    """Lookup table mapping every label value to an RGB colour (index 0 = black).

    Parameters
    ----------
    labels : ndarray of int
        Label image.
    colors : dict, optional
        Fixed colours for some labels; the others get :func:`distinct_colors`.

    Examples
    --------
    >>> labels = np.array([[0, 1, 1], [3, 3, 0]])
    >>> table = label_colors(labels, {3: (255, 0, 0)})  # region 3 red, the others distinct colours
    >>> table.tolist()
    [[0, 0, 0], [242, 85, 85], [85, 131, 242], [255, 0, 0]]
    >>> table[labels].shape  # the label image in colour
    (2, 3, 3)
    """
    n = int(labels.max()) + 1 if labels.size else 1
    table = np.zeros((n, 3), np.uint8)
    table[1:] = distinct_colors(n - 1)
    for label, color in (colors or {}).items():
        if 0 < label < n:
            table[label] = color
    return table


def _base_image(image: np.ndarray | None, free: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray:
    if image is not None:
        grey = np.asarray(image, np.uint8)
    elif free is not None:
        grey = np.where(free, 255, 0).astype(np.uint8)
    else:
        grey = np.full(shape, 255, np.uint8)
    return np.repeat(grey[..., None], 3, axis=2)


def _blended(base: np.ndarray, labels: np.ndarray, inside: np.ndarray, table: np.ndarray, opacity: float) -> np.ndarray:
    """``base`` with each labelled pixel blended towards its label's colour in ``table``.

    ``uint8((1 - opacity) * base + opacity * colour)`` computed in float32; a grey base (equal
    channels) goes through a 256 x 256 table of that same float32 expression, so the pixels
    are the same as the direct computation at a fraction of its time and memory.
    """
    if base.ndim != 3 or not (
        np.array_equal(base[..., 0], base[..., 1]) and np.array_equal(base[..., 0], base[..., 2])
    ):
        canvas = base.astype(np.float32)
        colours = table.astype(np.float32)
        canvas[inside] = (1 - opacity) * canvas[inside] + opacity * colours[labels[inside]]
        return canvas.astype(np.uint8)
    levels = np.arange(256, dtype=np.float32)
    lookup = ((1 - opacity) * levels[:, None] + opacity * levels[None, :]).astype(np.uint8)
    grey = base[..., 0]
    canvas = base.copy()
    # Most labelled pixels are free space, white in the map: their colour depends on the label
    # alone, one gather per pixel from a per-label row of the table (a 4000 x 4000 side of a
    # building figure: about 0.1 s instead of 1 s). The others, grey near the walls, go through
    # the whole table.
    white = inside & (grey == 255)
    # (OpenCV's masked copy: NumPy's copyto with a broadcast mask takes ten times as long.)
    # In bands of rows: np.take makes an intp copy of the labels it is given, 512 MB of fresh
    # memory for a whole 8000 x 8000 image (2 s of `ursim segment`'s overlay measured).
    colours, white_mask = lookup[255][table], white.view(np.uint8)
    for band in row_bands(labels):
        cv2.copyTo(np.take(colours, labels[band], axis=0), white_mask[band], canvas[band])
    where = np.flatnonzero(inside & ~white)
    regions = labels.ravel()[where]
    grey = grey.ravel()[where]
    pixels = canvas.reshape(-1, 3)
    for channel in range(3):
        pixels[where, channel] = lookup[grey, table[regions, channel]]
    return canvas


def _put_label(canvas: np.ndarray, text: str, row: float, col: float, scale: float) -> None:
    font = cv2.FONT_HERSHEY_SIMPLEX
    thickness = max(1, int(round(scale * 2)))
    (width, height), _ = cv2.getTextSize(text, font, scale, thickness)
    origin = (int(col - width / 2), int(row + height / 2))
    cv2.putText(canvas, text, origin, font, scale, (255, 255, 255), thickness + 2, cv2.LINE_AA)
    cv2.putText(canvas, text, origin, font, scale, (0, 0, 0), thickness, cv2.LINE_AA)


def overlay_segmentation(
    labels: np.ndarray,
    graph: nx.Graph,
    *,
    image: np.ndarray | None = None,
    free: np.ndarray | None = None,
    opacity: float = 0.55,
    colors: dict[int, Sequence[int]] | None = None,
    show_ids: bool = True,
    show_edges: bool = True,
    marked: Iterable[int] = (),
) -> np.ndarray:
    """Draw regions in colour over the map, with region ids and adjacency edges.

    Parameters
    ----------
    labels : ndarray of int, shape (rows, cols)
    graph : networkx.Graph or RegionTable
        Region graph with node attribute ``interior`` (row, col), or the same as a
        :class:`~ursim_core.segmentation.regions.RegionTable`.
    image, free : ndarray, optional
        The map's grey image (preferred) or free mask, drawn underneath.
    opacity : float
        Region colour opacity in [0, 1].
    colors : dict, optional
        Fixed colours per region (e.g. matched pairs sharing a colour).
    marked : iterable of int
        Regions drawn with a thick ring (anchors).

    Examples
    --------
    >>> labels = np.zeros((20, 30), np.int32); labels[2:18, 2:14] = 1; labels[2:18, 14:28] = 2
    >>> from ursim_core.segmentation.graph import region_graph
    >>> overlay_segmentation(labels, region_graph(labels)).shape
    (20, 30, 3)
    """
    labels = np.asarray(labels)
    inside = labels > 0
    canvas = _blended(_base_image(image, free, labels.shape), labels, inside, label_colors(labels, colors), opacity)
    outline = inside & (cv2.morphologyEx(labels.astype(np.float32), cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0)
    canvas[outline] = (40, 40, 40)
    scale = max(0.35, min(min(labels.shape) / 700, _TEXT_SCALE_MAX))
    if show_edges:
        for a, b in graph.edges:
            ra, ca = graph.nodes[a]["interior"]
            rb, cb = graph.nodes[b]["interior"]
            cv2.line(canvas, (int(ca), int(ra)), (int(cb), int(rb)), (30, 30, 30), max(1, int(scale * 2)), cv2.LINE_AA)
    for region in marked:
        if region in graph:
            row, col = graph.nodes[region]["interior"]
            cv2.circle(
                canvas, (int(col), int(row)), int(14 * scale + 6), (220, 20, 60), max(2, int(scale * 3)), cv2.LINE_AA
            )
    if show_ids:
        for region in graph.nodes:
            row, col = graph.nodes[region]["interior"]
            _put_label(canvas, str(region), row, col, scale)
    return canvas


def side_by_side_matches(
    sketch: tuple[np.ndarray, nx.Graph, np.ndarray | None],
    metric: tuple[np.ndarray, nx.Graph, np.ndarray | None],
    pairs: Sequence[tuple[int, int]],
    *,
    anchors: Sequence[tuple[int, int]] = (),
    gap: int = 24,
    max_side: int | None = FIGURE_MAX_SIDE,
) -> np.ndarray:
    """Both maps side by side, matched regions sharing a colour, connector lines, anchors ringed.

    ``sketch`` and ``metric`` are ``(labels, graph, grey_image_or_None)``. The metric map is
    scaled to the sketch's height so both read at a similar size. A map whose longer side
    exceeds ``max_side`` pixels is drawn scaled down to it (None: never): a building-sized
    map would otherwise give a figure of hundreds of megabytes that takes longer to draw
    than to match.

    Examples
    --------
    >>> from ursim_core.segmentation.graph import region_graph
    >>> labels = np.zeros((40, 60), np.int32); labels[2:38, 2:30] = 1; labels[2:38, 30:58] = 2
    >>> rooms = (labels, region_graph(labels), None)  # labels, region graph, grey image or None
    >>> figure = side_by_side_matches(rooms, rooms, [(1, 2)], gap=10)  # sketch region 1 is metric 2
    >>> figure.shape  # 60 px, the gap, 60 px
    (40, 130, 3)
    >>> figure[4, 4].tolist(), figure[4, 70 + 34].tolist(), figure[4, 34].tolist()  # unmatched: grey
    ([245, 136, 136], [245, 136, 136], [220, 220, 220])
    """
    pair_colors = distinct_colors(max(len(pairs), 1))
    grey = np.array((205, 205, 205), np.uint8)

    def side(drawn, regions, marked):
        """One map shrunk and drawn, its matched regions in their pair's colour."""
        labels, graph, image = _shrunk(*drawn, max_side)
        colors = {r: grey for r in graph.nodes}
        for index, region in enumerate(regions):
            colors[region] = pair_colors[index]
        overlay = overlay_segmentation(
            labels, graph, image=image, colors=colors, show_edges=False, marked=marked, opacity=0.7
        )
        return overlay, graph

    # The two maps on two threads: OpenCV and NumPy release the GIL (a building-sized pair draws
    # in about the time of one map); each side is drawn exactly as it would be alone.
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=2, thread_name_prefix="ursim-figure") as pool:
        left_job = pool.submit(side, sketch, [s for s, _ in pairs], [a for a, _ in anchors])
        right_job = pool.submit(side, metric, [m for _, m in pairs], [b for _, b in anchors])
        (left, sketch_graph), (right, metric_graph) = left_job.result(), right_job.result()
    scale = left.shape[0] / right.shape[0]
    right = cv2.resize(right, (max(1, round(right.shape[1] * scale)), left.shape[0]), interpolation=cv2.INTER_NEAREST)
    canvas = np.full((left.shape[0], left.shape[1] + gap + right.shape[1], 3), 255, np.uint8)
    canvas[:, : left.shape[1]] = left
    offset = left.shape[1] + gap
    canvas[:, offset:] = right
    for index, (s, m) in enumerate(pairs):
        if s not in sketch_graph or m not in metric_graph:
            continue
        rs, cs = sketch_graph.nodes[s]["interior"]
        rm, cm = metric_graph.nodes[m]["interior"]
        color = tuple(int(v) for v in pair_colors[index])
        cv2.line(canvas, (int(cs), int(rs)), (int(offset + cm * scale), int(rm * scale)), color, 2, cv2.LINE_AA)
    return canvas


def _shrunk(labels: np.ndarray, graph: Any, image: np.ndarray | None, max_side: int | None):
    """``(labels, graph, image)`` scaled so that the longer side is at most ``max_side``.

    Labels are resized by nearest neighbour, the grey image by area averaging, and the graph
    is replaced by one with the same nodes and their scaled ``interior`` points (no edges:
    the figure does not draw them).
    """
    labels = np.asarray(labels)
    longest = max(labels.shape) if labels.size else 0
    if max_side is None or longest <= max_side:
        return labels, graph, image
    factor = max_side / longest
    size = (max(1, round(labels.shape[1] * factor)), max(1, round(labels.shape[0] * factor)))
    small_labels = cv2.resize(labels.astype(np.int32, copy=False), size, interpolation=cv2.INTER_NEAREST)
    small_image = None
    if image is not None:
        small_image = cv2.resize(np.asarray(image, np.uint8), size, interpolation=cv2.INTER_AREA)
    import networkx as nx

    small_graph = nx.Graph()
    # Indexed, not nodes(data=...): a RegionTable's nodes are a dict, as overlay_segmentation allows.
    for region in graph.nodes:
        row, col = graph.nodes[region]["interior"]
        small_graph.add_node(region, interior=(row * factor, col * factor))
    return small_labels, small_graph, small_image


def save_png(path: str | Path, rgb: np.ndarray) -> None:
    """Write an RGB (or grey) uint8 image as PNG, atomically.

    Examples
    --------
    >>> import tempfile
    >>> from PIL import Image
    >>> rgb = np.zeros((2, 3, 3), np.uint8); rgb[0, 0] = (255, 0, 0)
    >>> path = Path(tempfile.mkdtemp()) / "figure.png"
    >>> save_png(path, rgb)
    >>> with Image.open(path) as png:
    ...     png.size, png.mode, png.getpixel((0, 0))  # Pillow's size is (width, height)
    ((3, 2), 'RGB', (255, 0, 0))
    """
    array = np.asarray(rgb)
    if array.ndim == 3:
        array = cv2.cvtColor(array, cv2.COLOR_RGB2BGR)
    ok, encoded = cv2.imencode(".png", array)
    if not ok:
        raise UrsimError("could not encode PNG", path=path)
    atomic_write_bytes(Path(path), encoded.tobytes())
