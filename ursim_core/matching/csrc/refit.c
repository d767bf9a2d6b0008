/* The refit's scale and shift per axis in C (module ``_matching_kernels``, see module.c).
 *
 * A port of ursim_core/matching/refit.py's fit_axis_transform after it has gathered the pairs'
 * centroids and weights: per axis, three rounds of a weighted line whose outlying pairs lose
 * their weight (Tukey's biweight at three median residuals). A turned KTH sketch is refitted
 * about 40 times; NumPy spent about 90 us on each fit of eight pairs, nearly all of it in the
 * overhead of its calls on tiny arrays. The sums run in index order, so a fit can differ from
 * NumPy's (whose dot products may pair terms differently) in the last bits; tests compare both.
 */
#include "kernels.h"

#include <math.h>
#include <stdlib.h>

enum { FIT_FOUND = 0, FIT_NONE = 1, FIT_DEGENERATE = 2 };

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* One axis: x and y with ``stride`` doubles between rows; ``scratch`` holds 2 n doubles. */
static int fit_axis(const double *x, const double *y, Py_ssize_t stride, const double *weights, Py_ssize_t n,
                    int rounds, double cutoff, double *scratch, double *slope_out, double *intercept_out)
{
    double *current = scratch, *residuals = scratch + n;
    double slope = 0.0, intercept = 0.0;
    for (Py_ssize_t k = 0; k < n; k++) {
        current[k] = weights[k];
    }
    for (int round = 0; round < rounds; round++) {
        Py_ssize_t nonzero = 0;
        for (Py_ssize_t k = 0; k < n; k++) {
            nonzero += current[k] != 0.0;
        }
        if (nonzero < 2) {
            return FIT_NONE;
        }
        double total = 0.0, sum_x = 0.0, sum_y = 0.0;
        for (Py_ssize_t k = 0; k < n; k++) {
            double squared = current[k] * current[k];
            total += squared;
            sum_x += squared * x[k * stride];
            sum_y += squared * y[k * stride];
        }
        double mean_x = sum_x / total, mean_y = sum_y / total;
        double spread = 0.0, moment = 0.0;
        for (Py_ssize_t k = 0; k < n; k++) {
            double squared = current[k] * current[k], dx = x[k * stride] - mean_x;
            spread += squared * (dx * dx);
            moment += squared * (dx * (y[k * stride] - mean_y));
        }
        if (!(spread > 1e-12 * total * fmax(1.0, mean_x * mean_x))) {
            return FIT_DEGENERATE; /* refit.py keeps lstsq's minimum-norm answer there */
        }
        slope = moment / spread;
        intercept = mean_y - slope * mean_x;
        for (Py_ssize_t k = 0; k < n; k++) {
            residuals[k] = fabs(slope * x[k * stride] + intercept - y[k * stride]);
        }
        /* The reweighting reads the residuals in order, so the median is taken from a copy. */
        double *sorted = current; /* the weights of this round are no longer needed */
        for (Py_ssize_t k = 0; k < n; k++) {
            sorted[k] = residuals[k];
        }
        qsort(sorted, (size_t)n, sizeof(double), by_value);
        double median = 0.5 * (sorted[(n - 1) / 2] + sorted[n / 2]);
        double reach = cutoff * median + 1e-9;
        for (Py_ssize_t k = 0; k < n; k++) {
            double ratio = residuals[k] / reach;
            double kept = 1.0 - ratio * ratio;
            kept = kept < 0.0 ? 0.0 : (kept > 1.0 ? 1.0 : kept);
            current[k] = weights[k] * (kept * kept);
        }
    }
    *slope_out = slope;
    *intercept_out = intercept;
    return FIT_FOUND;
}

/* fit_axes(source, target, weights, rounds, cutoff) -> ((row scale, row shift), (col scale, col
 * shift)), or 1 when a round keeps fewer than two pairs, or 2 when the weighted points of an axis
 * all but share one x (the caller fits that in NumPy). ``source`` and ``target`` are n x 2
 * doubles (row, col), ``weights`` n doubles. */
KERNEL(fit_axes)
{
    if (check_nargs("fit_axes", nargs, 5) < 0) {
        return NULL;
    }
    Py_buffer views[3];
    int n_views = 0;
    PyObject *result = NULL;
    double *scratch = NULL;
    if (get_buffer(args[0], 8, 'f', 2, "fit_axes: source", &views[n_views]) < 0) goto done;
    n_views++;
    if (get_buffer(args[1], 8, 'f', 2, "fit_axes: target", &views[n_views]) < 0) goto done;
    n_views++;
    if (get_buffer(args[2], 8, 'f', 1, "fit_axes: weights", &views[n_views]) < 0) goto done;
    n_views++;
    long rounds = PyLong_AsLong(args[3]);
    double cutoff = PyFloat_AsDouble(args[4]);
    if (PyErr_Occurred()) goto done;
    Py_ssize_t n = views[2].shape[0];
    if (views[0].shape[0] != n || views[1].shape[0] != n || views[0].shape[1] != 2 || views[1].shape[1] != 2
        || n < 1 || rounds < 1) {
        PyErr_SetString(PyExc_ValueError, "fit_axes: source and target must be n x 2, weights n, rounds >= 1");
        goto done;
    }
    scratch = malloc(sizeof(double) * 2 * (size_t)n);
    if (scratch == NULL) {
        PyErr_NoMemory();
        goto done;
    }
    const double *source = views[0].buf, *target = views[1].buf, *weights = views[2].buf;
    double fitted[4];
    int status = FIT_FOUND;
    for (int axis = 0; axis < 2 && status == FIT_FOUND; axis++) {
        status = fit_axis(source + axis, target + axis, 2, weights, n, (int)rounds, cutoff, scratch,
                          &fitted[2 * axis], &fitted[2 * axis + 1]);
    }
    result = status == FIT_FOUND ? Py_BuildValue("((dd)(dd))", fitted[0], fitted[1], fitted[2], fitted[3])
                                 : PyLong_FromLong(status);
done:
    for (int k = 0; k < n_views; k++) {
        PyBuffer_Release(&views[k]);
    }
    free(scratch);
    return result;
}
