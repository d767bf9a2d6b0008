/* Painting the inscribed discs of MAORIS step 1 in C (port of ../kernels/discs.py, whose
 * docstrings explain the method: non-dominated centres grouped into rectangles, then each
 * rectangle's disc rows painted, one-pixel shapes only where their neighbours leave gaps). */
#include "kernels.h"

enum { TOP = 0, BOTTOM = 1, LEFT = 2, RIGHT = 3, RADIUS = 4, DIAGONALS = 5 };
enum { UP_LEFT = 1, UP_RIGHT = 2, DOWN_LEFT = 4, DOWN_RIGHT = 8 };
#define ABOVE (UP_LEFT | UP_RIGHT)
#define BELOW (DOWN_LEFT | DOWN_RIGHT)
/* One-pixel shapes up to this reach paint only what their diagonal neighbours leave uncovered. */
#define TRIMMED_REACH_LIMIT 512

static inline int32_t max32(int32_t a, int32_t b) { return a > b ? a : b; }

static void load_radii(const float *dist_row, int64_t cols, int64_t max_radius, int32_t *into)
{
    for (int64_t col = 0; col < cols; col++) {
        float value = dist_row[col];
        /* numba compares a float32 with an int64 in float64 */
        into[col + 1] = (double)value >= (double)max_radius ? (int32_t)max_radius : (int32_t)value;
    }
}

/* discs.centre_rectangles over rows first_row .. end_row - 1 (the rows around them read too):
 * the rectangles created there, as if the rows above did not exist (a rectangle that goes on
 * from the row above starts again at first_row), in the malloc'd b->shapes; b->open_at: the
 * last rectangle created at each column. b->failed when out of memory. */
typedef struct {
    const float *dist;
    int64_t rows, cols, max_radius, first_row, end_row;
    int64_t *shapes, capacity, count, *open_at;
    int32_t *ring, *centre_radius;
    int failed;
} CentreBand;

/* A band's buffers, allocated on the calling thread: glibc keeps what a thread allocates in
 * that thread's arena, where it stays resident once freed (the band's realloc keeps its arena). */
static int centre_band_buffers(CentreBand *b)
{
    int64_t cols = b->cols, band_pixels = (b->end_row - b->first_row) * cols;
    b->capacity = band_pixels / 64 > 16 ? band_pixels / 64 : 16;
    b->ring = calloc((size_t)(3 * (cols + 2)), sizeof(int32_t));
    b->centre_radius = calloc((size_t)(cols + 1), sizeof(int32_t));
    b->open_at = malloc((size_t)(cols > 0 ? cols : 1) * sizeof(int64_t));
    b->shapes = malloc((size_t)b->capacity * 6 * sizeof(int64_t));
    return b->ring == NULL || b->centre_radius == NULL || b->open_at == NULL || b->shapes == NULL ? -1 : 0;
}

static void *centre_band(void *arg)
{
    CentreBand *b = arg;
    const float *dist = b->dist;
    int64_t rows = b->rows, cols = b->cols, max_radius = b->max_radius;
    int32_t *ring = b->ring, *centre_radius = b->centre_radius;
    int64_t *open_at = b->open_at, *shapes = b->shapes, capacity = b->capacity, count = 0;
    int64_t first = b->first_row;
    if (first > 0) {
        load_radii(dist + (first - 1) * cols, cols, max_radius, ring + ((first + 2) % 3) * (cols + 2));
    }
    if (first < rows) {
        load_radii(dist + first * cols, cols, max_radius, ring + (first % 3) * (cols + 2));
    }
    for (int64_t col = 0; col < cols; col++) {
        open_at[col] = -1;
    }
    for (int64_t row = first; row < b->end_row; row++) {
        int32_t *up = ring + ((row + 2) % 3) * (cols + 2), *here = ring + (row % 3) * (cols + 2);
        int32_t *down = ring + ((row + 1) % 3) * (cols + 2);
        if (row + 1 < rows) {
            load_radii(dist + (row + 1) * cols, cols, max_radius, down);
        } else {
            memset(down, 0, (size_t)(cols + 2) * sizeof(int32_t));
        }
        for (int64_t col = 0; col < cols; col++) {
            int64_t radius = here[col + 1];
            int64_t side = max32(max32(here[col], here[col + 2]), max32(up[col + 1], down[col + 1]));
            int64_t corner = max32(max32(up[col], up[col + 2]), max32(down[col], down[col + 2]));
            centre_radius[col] = (radius > 0) & (side <= radius) & (corner <= radius + 1) ? (int32_t)radius : 0;
        }
        if (count + cols > capacity) {
            int64_t grown_capacity = 2 * capacity + cols;
            int64_t *grown = realloc(shapes, (size_t)grown_capacity * 6 * sizeof(int64_t));
            if (grown == NULL) {
                goto fail;
            }
            shapes = grown;
            capacity = grown_capacity;
        }
        int64_t col = 0;
        while (col < cols) {
            int64_t radius = centre_radius[col];
            if (radius == 0) {
                col += 1;
                continue;
            }
            int64_t last = col;
            while (centre_radius[last + 1] == radius) {
                last += 1;
            }
            int64_t shape = open_at[col];
            if (shape >= 0 && shapes[6 * shape + BOTTOM] == row - 1 && shapes[6 * shape + RIGHT] == last
                && shapes[6 * shape + RADIUS] == radius) {
                shapes[6 * shape + BOTTOM] = row;
                shapes[6 * shape + DIAGONALS] = 0;
            } else {
                int64_t *entry = shapes + 6 * count;
                entry[TOP] = row;
                entry[BOTTOM] = row;
                entry[LEFT] = col;
                entry[RIGHT] = last;
                entry[RADIUS] = radius;
                int64_t diagonals = 0;
                if (last == col) {
                    int64_t larger = radius + 1;
                    diagonals = (up[col] == larger) * UP_LEFT + (up[col + 2] == larger) * UP_RIGHT
                                + (down[col] == larger) * DOWN_LEFT + (down[col + 2] == larger) * DOWN_RIGHT;
                }
                entry[DIAGONALS] = diagonals;
                open_at[col] = count;
                count += 1;
            }
            col = last + 1;
        }
    }
    b->shapes = shapes;
    b->count = count;
    return NULL;
fail:
    b->shapes = shapes; /* freed by the caller */
    b->failed = 1;
    return NULL;
}

/* discs.centre_rectangles; returns the malloc'd (count, 6) table, or NULL when out of memory.
 * Large images are scanned in bands of rows, one thread each; a rectangle that a band starts on
 * its first row is then joined to the one it goes on from (the last created at its column in
 * the band above, which ends on the row above with the same right end and radius), as one
 * scan of all rows would have grown it: the same rectangles in the same order. */
static int64_t *centre_rectangles(const float *dist, int64_t rows, int64_t cols, int64_t max_radius, int64_t *count_out)
{
    int64_t n_bands = parts_for(rows * cols, rows);
    CentreBand bands[MAX_BANDS];
    int failed = 0;
    for (int64_t k = 0; k < n_bands; k++) {
        bands[k] = (CentreBand){dist, rows, cols, max_radius, rows * k / n_bands, rows * (k + 1) / n_bands};
        failed |= centre_band_buffers(&bands[k]) < 0;
    }
    int64_t *shapes = NULL, *start = NULL, *alias = NULL, total = 0;
    if (failed) {
        goto done;
    }
    run_parts(bands, n_bands, sizeof(CentreBand), centre_band);
    for (int64_t k = 0; k < n_bands; k++) {
        failed |= bands[k].failed;
    }
    if (failed) {
        goto done;
    }
    for (int64_t k = 0; k < n_bands; k++) {
        total += bands[k].count;
    }
    if (n_bands == 1) {
        shapes = bands[0].shapes, bands[0].shapes = NULL;
        *count_out = total;
        goto done;
    }
    /* Every band's rectangles by one index (band k's i-th: start[k] + i); alias: the index a
     * joined rectangle went into (itself when kept). */
    start = malloc((size_t)(n_bands + 1) * sizeof(int64_t));
    alias = malloc((size_t)(total > 0 ? total : 1) * sizeof(int64_t));
    /* The first band's table grown to hold them all (its pages are there already). */
    shapes = start == NULL || alias == NULL ? NULL : realloc(bands[0].shapes, (size_t)(total + 1) * 6 * sizeof(int64_t));
    if (shapes == NULL) {
        goto done;
    }
    bands[0].shapes = NULL;
    start[0] = 0;
    for (int64_t k = 0; k < n_bands; k++) {
        start[k + 1] = start[k] + bands[k].count;
        if (k > 0) {
            memcpy(shapes + 6 * start[k], bands[k].shapes, (size_t)bands[k].count * 6 * sizeof(int64_t));
        }
    }
    for (int64_t i = 0; i < total; i++) {
        alias[i] = i;
    }
    for (int64_t k = 1; k < n_bands; k++) {
        int64_t row = bands[k].first_row;
        const int64_t *open_above = bands[k - 1].open_at;
        for (int64_t i = start[k]; i < start[k + 1] && shapes[6 * i + TOP] == row; i++) {
            int64_t *shape = shapes + 6 * i;
            int64_t above = open_above[shape[LEFT]];
            if (above < 0) {
                continue;
            }
            above = alias[start[k - 1] + above];
            int64_t *into = shapes + 6 * above;
            if (into[BOTTOM] == row - 1 && into[RIGHT] == shape[RIGHT] && into[RADIUS] == shape[RADIUS]) {
                into[BOTTOM] = shape[BOTTOM];
                into[DIAGONALS] = 0;
                alias[i] = above;
            }
        }
    }
    int64_t kept = 0;
    for (int64_t i = 0; i < total; i++) {
        if (alias[i] == i) {
            memmove(shapes + 6 * kept, shapes + 6 * i, 6 * sizeof(int64_t));
            kept += 1;
        }
    }
    *count_out = kept;
done:
    for (int64_t k = 0; k < n_bands; k++) {
        free(bands[k].shapes);
        free(bands[k].open_at);
        free(bands[k].ring);
        free(bands[k].centre_radius);
    }
    free(start);
    free(alias);
    return shapes;
}

KERNEL(centre_rectangles)
{
    Array dist;
    int64_t max_radius, count = 0;
    if (check_nargs("centre_rectangles", nargs, 2) || array_arg(args[0], NPY_FLOAT32, 2, 0, "dist", &dist)
        || int_arg(args[1], "max_radius", &max_radius)) {
        return NULL;
    }
    int64_t *shapes;
    Py_BEGIN_ALLOW_THREADS
    shapes = centre_rectangles(dist.data, dist.rows, dist.cols, max_radius, &count);
    Py_END_ALLOW_THREADS
    if (shapes == NULL) {
        return PyErr_NoMemory();
    }
    npy_intp dims[2] = {count, 6};
    return array_owning(shapes, 2, dims, NPY_INT64);
}

/* discs._uncovered_pieces: the pieces of a one-pixel shape's disc that its diagonal neighbours
 * leave uncovered, for every reach up to largest_reach. Returns 0, or -1 when out of memory. */
typedef struct {
    int64_t *start;
    int32_t *distance, *from, *to;
} Pieces;

static int uncovered_pieces(int64_t largest_reach, Pieces *pieces)
{
    int64_t *half_width = malloc((size_t)((largest_reach + 2) * (largest_reach + 3) / 2) * sizeof(int64_t));
    int64_t capacity = 6 * (largest_reach + 1) * (largest_reach + 2) / 2;
    pieces->start = calloc((size_t)(3 * (largest_reach + 1) + 1), sizeof(int64_t));
    pieces->distance = malloc((size_t)(capacity > 0 ? capacity : 1) * sizeof(int32_t));
    pieces->from = malloc((size_t)(capacity > 0 ? capacity : 1) * sizeof(int32_t));
    pieces->to = malloc((size_t)(capacity > 0 ? capacity : 1) * sizeof(int32_t));
    if (half_width == NULL || pieces->start == NULL || pieces->distance == NULL || pieces->from == NULL
        || pieces->to == NULL) {
        free(half_width);
        return -1;
    }
    for (int64_t reach = 0; reach < largest_reach + 2; reach++) {
        int64_t width = reach;
        for (int64_t d = 0; d <= reach; d++) {
            while (width * width + d * d > reach * reach) {
                width -= 1;
            }
            half_width[reach * (reach + 1) / 2 + d] = width;
        }
    }
    int64_t count = 0;
    for (int64_t reach = 0; reach <= largest_reach; reach++) {
        for (int64_t neighbours = 1; neighbours < 4; neighbours++) {
            for (int64_t d = 0; d <= reach; d++) {
                int64_t width = half_width[reach * (reach + 1) / 2 + d];
                int64_t covering = half_width[(reach + 1) * (reach + 2) / 2 + d + 1];
                int64_t covered_from = ((neighbours & 1) ? -1 : 1) - covering;
                int64_t covered_to = ((neighbours & 2) ? 1 : -1) + covering;
                int64_t firsts[2] = {-width, -width > covered_to + 1 ? -width : covered_to + 1};
                int64_t lasts[2] = {width < covered_from - 1 ? width : covered_from - 1, width};
                for (int k = 0; k < 2; k++) {
                    if (firsts[k] <= lasts[k]) {
                        pieces->distance[count] = (int32_t)d;
                        pieces->from[count] = (int32_t)firsts[k];
                        pieces->to[count] = (int32_t)lasts[k];
                        count += 1;
                    }
                }
            }
            pieces->start[3 * reach + neighbours] = count;
        }
    }
    free(half_width);
    return 0;
}

static inline void raise_span(int32_t *out_row, int64_t cols, int64_t first_col, int64_t last_col, int64_t radius)
{
    int64_t from = first_col > 0 ? first_col : 0, to = last_col < cols - 1 ? last_col : cols - 1;
    for (int64_t col = from; col <= to; col++) {
        out_row[col] = out_row[col] > radius ? out_row[col] : (int32_t)radius;
    }
}

/* What every band of a painting reads: the shapes, the pieces, the free mask and the output. */
typedef struct {
    const int64_t *shapes;
    int64_t n, rows, cols, reach_cap, trimmed_reach_limit;
    const Pieces *pieces;
    const Array *free_mask;
    int32_t *out;
} Painting;

/* One band of a painting: rows first_row .. end_row - 1 of every disc, then the obstacles
 * there set to 0. Each pixel keeps the largest radius painted over it, so bands painted apart
 * give the image painted whole. */
typedef struct {
    const Painting *painting;
    int64_t first_row, end_row;
} Band;

static void paint_band(const Painting *p, int64_t first_row, int64_t end_row)
{
    int64_t cols = p->cols;
    int32_t *out = p->out;
    for (int64_t i = 0; i < p->n; i++) {
        const int64_t *shape = p->shapes + 6 * i;
        int64_t radius = shape[RADIUS];
        int64_t reach = radius - 1 < p->reach_cap ? radius - 1 : p->reach_cap;
        int64_t top = shape[TOP] - 1, bottom = shape[BOTTOM] - 1, left = shape[LEFT] - 1, right = shape[RIGHT] - 1;
        if (bottom + reach < first_row || top - reach >= end_row) {
            continue;
        }
        int64_t diagonals = reach < p->trimmed_reach_limit ? shape[DIAGONALS] : 0;
        if (diagonals == 0) {
            int64_t width = 0;
            int64_t from_row = top - reach > first_row ? top - reach : first_row;
            int64_t to_row = bottom + reach < end_row - 1 ? bottom + reach : end_row - 1;
            for (int64_t row = from_row; row <= to_row; row++) {
                int64_t d = top - row > row - bottom ? top - row : row - bottom;
                d = d > 0 ? d : 0;
                /* the widest span of the disc at distance d: from any start, both loops end on it */
                while ((width + 1) * (width + 1) + d * d <= reach * reach) {
                    width += 1;
                }
                while (width * width + d * d > reach * reach) {
                    width -= 1;
                }
                if (0 <= row && row < p->rows) {
                    raise_span(out + row * cols, cols, left - width, right + width, radius);
                }
            }
            continue;
        }
        int below = (diagonals & BELOW) != 0;
        int64_t step = below ? -1 : 1;
        int64_t neighbours = below ? diagonals >> 2 : diagonals & ABOVE;
        int64_t farthest = ((diagonals & ABOVE) && below) ? 0 : reach;
        int64_t key = reach * 3 + neighbours;
        for (int64_t piece = p->pieces->start[key - 1]; piece < p->pieces->start[key]; piece++) {
            if (p->pieces->distance[piece] > farthest) {
                break;
            }
            int64_t row = top + step * p->pieces->distance[piece];
            if (first_row <= row && row < end_row) {
                raise_span(out + row * cols, cols, left + p->pieces->from[piece], left + p->pieces->to[piece], radius);
            }
        }
    }
    const Array *free_mask = p->free_mask;
    const uint8_t *free_data = free_mask->data;
    for (int64_t row = first_row; row < end_row; row++) {
        const uint8_t *free_row = free_data + row * free_mask->row_stride;
        for (int64_t col = 0; col < cols; col++) {
            if (free_row[col * free_mask->col_stride] == 0) {
                out[row * cols + col] = 0;
            }
        }
    }
}

static void *paint_band_run(void *arg)
{
    Band *band = arg;
    paint_band(band->painting, band->first_row, band->end_row);
    return NULL;
}

static int paint(const int64_t *shapes, int64_t n, const Array *free_mask, int32_t *out, int64_t rows, int64_t cols)
{
    int64_t reach_cap = rows + cols;
    int64_t trimmed_reach_limit = TRIMMED_REACH_LIMIT < reach_cap ? TRIMMED_REACH_LIMIT : reach_cap;
    int64_t largest_trimmed = -1;
    for (int64_t i = 0; i < n; i++) {
        const int64_t *shape = shapes + 6 * i;
        if (shape[DIAGONALS] != 0 && shape[RADIUS] - 1 < trimmed_reach_limit && shape[RADIUS] - 1 > largest_trimmed) {
            largest_trimmed = shape[RADIUS] - 1;
        }
    }
    Pieces pieces = {0};
    int failed = uncovered_pieces(largest_trimmed, &pieces);
    if (!failed) {
        Painting painting = {shapes, n, rows, cols, reach_cap, trimmed_reach_limit, &pieces, free_mask, out};
        /* Large images are painted in bands of rows, one thread each (the bands write
         * different rows); smaller ones on this thread, where starting threads costs more. */
        int64_t n_bands = parts_for(rows * cols, rows);
        Band bands[MAX_BANDS];
        for (int64_t k = 0; k < n_bands; k++) {
            bands[k] = (Band){&painting, rows * k / n_bands, rows * (k + 1) / n_bands};
        }
        run_parts(bands, n_bands, sizeof(Band), paint_band_run);
    }
    free(pieces.start);
    free(pieces.distance);
    free(pieces.from);
    free(pieces.to);
    return failed;
}

KERNEL(paint_discs)
{
    Array shapes, free_mask, out;
    if (check_nargs("paint_discs", nargs, 3) || array_arg(args[0], NPY_INT64, 2, 0, "shapes", &shapes)
        || array_arg(args[1], NPY_UINT8, 2, 1, "free", &free_mask) || array_arg(args[2], NPY_INT32, 2, 0, "out", &out)) {
        return NULL;
    }
    if (shapes.cols != 6 || free_mask.rows != out.rows || free_mask.cols != out.cols) {
        PyErr_SetString(PyExc_ValueError, "paint_discs: shapes must have 6 columns, free and out one shape");
        return NULL;
    }
    int failed;
    Py_BEGIN_ALLOW_THREADS
    failed = paint(shapes.data, shapes.rows, &free_mask, out.data, out.rows, out.cols);
    Py_END_ALLOW_THREADS
    if (failed) {
        return PyErr_NoMemory();
    }
    Py_RETURN_NONE;
}
