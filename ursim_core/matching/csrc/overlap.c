/* The orientation overlap's pattern search in C (module ``_matching_kernels``, see module.c).
 *
 * A port of the search in ursim_core/matching/alignment.py's _fit, which stays the reference:
 * the same steps in the same order, the same transform per point (plain double arithmetic, no
 * fused multiply-adds: native.CFLAGS), and the overlap of OpenCV's nearest-neighbour warpAffine
 * (BORDER_CONSTANT 0) computed as OpenCV 4 computes the warp: the matrix inverted in doubles,
 * source coordinates in fixed point with 10 fractional bits, rounded half to even. Instead of
 * the warped image, only its two counts are made (free pixels, and free pixels on the target's),
 * and each row only over the columns whose source pixel lies inside the sketch: the source
 * column and row are monotone along a row, so those columns are one interval.
 *
 * Why C: the first segmentation of a turned KTH sketch fits eight orientations, about 96
 * overlaps each; OpenCV's warp and Python around it took about 13 us an overlap.
 */
#include "kernels.h"

#include <math.h>
#include <stdlib.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

enum { AB_BITS = 10, AB_SCALE = 1 << AB_BITS, N_PARAMS = 5 };

typedef struct {
    const uint8_t *sketch, *target;
    int32_t sketch_rows, sketch_cols, target_rows, target_cols;
    int64_t target_area;
    double t00, t01, t10, t11;             /* the candidate orientation's turn */
    double scale_rows, scale_cols;         /* the box-to-box scale */
    double centre_rows, centre_cols;       /* the sketch point sent to the metric box centre */
    double metric_centre[2], metric_extent[2];
    double to_coarse, factor;              /* sketch pixels to coarse metric pixels; metric shrink */
    int32_t *adelta, *bdelta;              /* target_cols each */
} Search;

/* cvRound: to the nearest int, halves to even (OpenCV's saturate_cast<int> of a double). The SSE2
 * conversion is what OpenCV uses on x86 and is inlined, where lrint is a libm call (about 330 a
 * warp); both round by the current mode, nearest-even. */
static inline int32_t round_even(double value)
{
#if defined(__SSE2__)
    return _mm_cvtsd_si32(_mm_set_sd(value));
#else
    return (int32_t)lrint(value);
#endif
}

/* alignment._fit's linear_offset: (l00, l01, l10, l11, o0, o1) of a parameter vector. */
static void linear_offset(const Search *s, const double *params, double *out)
{
    double c = cos(params[4]), n = sin(params[4]);
    double a = s->scale_rows * exp(params[0]), d = s->scale_cols * exp(params[1]);
    double m00 = a * s->t00, m01 = a * s->t01, m10 = d * s->t10, m11 = d * s->t11;
    double l00 = c * m00 - n * m10, l01 = c * m01 - n * m11, l10 = n * m00 + c * m10, l11 = n * m01 + c * m11;
    out[0] = l00;
    out[1] = l01;
    out[2] = l10;
    out[3] = l11;
    out[4] = s->metric_centre[0] + params[2] * s->metric_extent[0] - (l00 * s->centre_rows + l01 * s->centre_cols);
    out[5] = s->metric_centre[1] + params[3] * s->metric_extent[1] - (l10 * s->centre_rows + l11 * s->centre_cols);
}

/* OpenCV's source coordinate: (offset + delta) >> AB_BITS in int arithmetic, which wraps (as
 * OpenCV's does) instead of overflowing, for the absurd matrices of a degenerate fit. */
static inline int32_t source_coordinate(int32_t offset, int32_t delta)
{
    return (int32_t)((uint32_t)offset + (uint32_t)delta) >> AB_BITS;
}

/* The first and one past the last x in [0, cols) where lo <= value(x) < hi, for a value that is
 * monotone in x (non-decreasing when ``rising``); *first >= *stop when there is none. */
static void monotone_interval(const int32_t *base, int32_t offset, int32_t cols, int32_t lo, int32_t hi, int rising,
                              int32_t *first, int32_t *stop)
{
    /* value(x) = source_coordinate(offset, base[x]) */
    int32_t low = 0, high = cols;
    if (rising) {
        while (low < high) { /* first x with value >= lo */
            int32_t mid = low + (high - low) / 2;
            if (source_coordinate(offset, base[mid]) >= lo) high = mid; else low = mid + 1;
        }
        *first = low;
        low = *first, high = cols;
        while (low < high) { /* first x with value >= hi */
            int32_t mid = low + (high - low) / 2;
            if (source_coordinate(offset, base[mid]) >= hi) high = mid; else low = mid + 1;
        }
        *stop = low;
    } else {
        while (low < high) { /* first x with value < hi */
            int32_t mid = low + (high - low) / 2;
            if (source_coordinate(offset, base[mid]) < hi) high = mid; else low = mid + 1;
        }
        *first = low;
        low = *first, high = cols;
        while (low < high) { /* first x with value < lo */
            int32_t mid = low + (high - low) / 2;
            if (source_coordinate(offset, base[mid]) < lo) high = mid; else low = mid + 1;
        }
        *stop = low;
    }
}

/* alignment._fit's overlap_of: the intersection over union of the warped sketch and the target. */
static double overlap_of(const Search *s, const double *params)
{
    double l[6];
    linear_offset(s, params, l);
    double k = s->to_coarse, f = s->factor;
    double half = 0.5 * (k - f);
    double c0 = f * l[4] + half * (l[0] + l[1]) + 0.5 * f - 0.5;
    double c1 = f * l[5] + half * (l[2] + l[3]) + 0.5 * f - 0.5;
    /* OpenCV's (x, y) matrix, then inverted as cv::warpAffine inverts it. */
    double M[6] = {l[3] * k, l[2] * k, c1, l[1] * k, l[0] * k, c0};
    double D = M[0] * M[4] - M[1] * M[3];
    D = D != 0 ? 1. / D : 0;
    double A11 = M[4] * D, A22 = M[0] * D;
    M[0] = A11;
    M[1] *= -D;
    M[3] *= -D;
    M[4] = A22;
    double b1 = -M[0] * M[2] - M[1] * M[5];
    double b2 = -M[3] * M[2] - M[4] * M[5];
    M[2] = b1;
    M[5] = b2;
    int32_t cols = s->target_cols;
    for (int32_t x = 0; x < cols; x++) {
        s->adelta[x] = round_even(M[0] * x * AB_SCALE);
        s->bdelta[x] = round_even(M[3] * x * AB_SCALE);
    }
    int rising_x = cols < 2 || s->adelta[cols - 1] >= s->adelta[0];
    int rising_y = cols < 2 || s->bdelta[cols - 1] >= s->bdelta[0];
    int64_t warped = 0, inter = 0;
    for (int32_t y = 0; y < s->target_rows; y++) {
        int32_t X0 = round_even((M[1] * y + M[2]) * AB_SCALE) + AB_SCALE / 2;
        int32_t Y0 = round_even((M[4] * y + M[5]) * AB_SCALE) + AB_SCALE / 2;
        int32_t first_x, stop_x, first_y, stop_y;
        monotone_interval(s->adelta, X0, cols, 0, s->sketch_cols, rising_x, &first_x, &stop_x);
        monotone_interval(s->bdelta, Y0, cols, 0, s->sketch_rows, rising_y, &first_y, &stop_y);
        int32_t first = first_x > first_y ? first_x : first_y, stop = stop_x < stop_y ? stop_x : stop_y;
        const uint8_t *target_row = s->target + (int64_t)y * cols;
        for (int32_t x = first; x < stop; x++) {
            int32_t X = source_coordinate(X0, s->adelta[x]), Y = source_coordinate(Y0, s->bdelta[x]);
            uint8_t value = s->sketch[(int64_t)Y * s->sketch_cols + X];
            warped += value != 0;
            inter += (value & target_row[x]) != 0;
        }
    }
    int64_t total = warped + s->target_area - inter;
    return total ? (double)inter / (double)total : 0.0;
}

/* overlap_search(sketch, target, target_area, turn(4), scale(2), centre(2), metric_centre(2),
 * metric_extent(2), to_coarse, factor, first_steps(5), smallest_step, max_rounds)
 * -> (best overlap, (log row scale, log col scale, row shift, col shift, turn)).
 * ``sketch`` and ``target`` are C-contiguous uint8 images; the numbers are tuples of floats. */
KERNEL(overlap_search)
{
    if (check_nargs("overlap_search", nargs, 13) < 0) {
        return NULL;
    }
    Py_buffer views[2];
    int n_views = 0;
    PyObject *result = NULL;
    Search s;
    s.adelta = NULL;
    double (*seen)[N_PARAMS + 1] = NULL;
    if (get_buffer(args[0], 1, 'b', 2, "overlap_search: sketch", &views[n_views]) < 0) goto done;
    n_views++;
    if (get_buffer(args[1], 1, 'b', 2, "overlap_search: target", &views[n_views]) < 0) goto done;
    n_views++;
    double numbers[20];
    const Py_ssize_t sizes[8] = {4, 2, 2, 2, 2, 1, 1, 5};
    int at = 0;
    for (int k = 0; k < 8; k++) {
        PyObject *item = args[3 + k];
        if (sizes[k] == 1) {
            numbers[at++] = PyFloat_AsDouble(item);
            continue;
        }
        if (!PyTuple_Check(item) || PyTuple_GET_SIZE(item) != sizes[k]) {
            PyErr_SetString(PyExc_TypeError, "overlap_search: the numbers must be tuples of the documented sizes");
            goto done;
        }
        for (Py_ssize_t j = 0; j < sizes[k]; j++) {
            numbers[at++] = PyFloat_AsDouble(PyTuple_GET_ITEM(item, j));
        }
    }
    long long target_area = PyLong_AsLongLong(args[2]);
    double smallest_step = PyFloat_AsDouble(args[11]);
    long max_rounds = PyLong_AsLong(args[12]);
    if (PyErr_Occurred()) goto done;
    s.sketch = views[0].buf;
    s.target = views[1].buf;
    s.sketch_rows = (int32_t)views[0].shape[0];
    s.sketch_cols = (int32_t)views[0].shape[1];
    s.target_rows = (int32_t)views[1].shape[0];
    s.target_cols = (int32_t)views[1].shape[1];
    s.target_area = target_area;
    s.t00 = numbers[0], s.t01 = numbers[1], s.t10 = numbers[2], s.t11 = numbers[3];
    s.scale_rows = numbers[4], s.scale_cols = numbers[5];
    s.centre_rows = numbers[6], s.centre_cols = numbers[7];
    s.metric_centre[0] = numbers[8], s.metric_centre[1] = numbers[9];
    s.metric_extent[0] = numbers[10], s.metric_extent[1] = numbers[11];
    s.to_coarse = numbers[12], s.factor = numbers[13];
    const double *first_steps = numbers + 14;
    if (s.sketch_rows < 1 || s.sketch_cols < 1 || s.target_rows < 1 || s.target_cols < 1 || max_rounds < 0) {
        PyErr_SetString(PyExc_ValueError, "overlap_search: empty image or negative rounds");
        goto done;
    }
    s.adelta = malloc(sizeof(int32_t) * 2 * (size_t)s.target_cols);
    /* Every point scored, to look up a step back instead of warping again: at most one start and
     * ten trials per round. */
    size_t capacity = 1 + 2 * N_PARAMS * (size_t)(max_rounds + 1);
    seen = malloc(sizeof(*seen) * capacity);
    if (s.adelta == NULL || seen == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    s.bdelta = s.adelta + s.target_cols;
    double params[N_PARAMS] = {0.0, 0.0, 0.0, 0.0, 0.0}, steps[N_PARAMS], best;
    for (int k = 0; k < N_PARAMS; k++) {
        steps[k] = first_steps[k];
    }
    size_t n_seen = 0;
    Py_BEGIN_ALLOW_THREADS
    best = overlap_of(&s, params);
    for (int k = 0; k < N_PARAMS; k++) {
        seen[n_seen][k] = params[k];
    }
    seen[n_seen++][N_PARAMS] = best;
    for (long round = 0; round < max_rounds; round++) {
        int improved = 0;
        for (int axis = 0; axis < N_PARAMS; axis++) {
            for (int sign = 0; sign < 2; sign++) {
                double trial[N_PARAMS];
                for (int k = 0; k < N_PARAMS; k++) {
                    trial[k] = params[k];
                }
                trial[axis] += (sign ? -1.0 : 1.0) * steps[axis];
                double value = -1.0;
                for (size_t i = 0; i < n_seen && value < 0; i++) {
                    int same = 1;
                    for (int k = 0; k < N_PARAMS && same; k++) {
                        same = seen[i][k] == trial[k];
                    }
                    if (same) {
                        value = seen[i][N_PARAMS];
                    }
                }
                if (value < 0) {
                    value = overlap_of(&s, trial);
                    for (int k = 0; k < N_PARAMS; k++) {
                        seen[n_seen][k] = trial[k];
                    }
                    seen[n_seen++][N_PARAMS] = value;
                }
                if (value > best + 1e-12) {
                    best = value;
                    for (int k = 0; k < N_PARAMS; k++) {
                        params[k] = trial[k];
                    }
                    improved = 1;
                }
            }
        }
        if (!improved) {
            double largest = 0.0;
            for (int k = 0; k < N_PARAMS; k++) {
                steps[k] = steps[k] / 2;
                largest = steps[k] > largest || k == 0 ? steps[k] : largest;
            }
            if (largest < smallest_step) {
                break;
            }
        }
    }
    Py_END_ALLOW_THREADS
    result = Py_BuildValue("(d(ddddd))", best, params[0], params[1], params[2], params[3], params[4]);
done:
    for (int k = 0; k < n_views; k++) {
        PyBuffer_Release(&views[k]);
    }
    free(s.adelta);
    free(seen);
    return result;
}
